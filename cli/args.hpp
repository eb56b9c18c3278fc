// A small command-line parser shared by the robocal subcommands: `--name value`, `--flag`, and
// positional arguments. Unknown options and missing values are errors that name the option.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace robocal::cli {

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Args {
 public:
  // `valued` lists options that take a value, `flags` those that do not (names without "--").
  // Options listed in `repeatable` may be given more than once.
  Args(const std::vector<std::string>& argv, const std::set<std::string>& valued,
       const std::set<std::string>& flags, const std::set<std::string>& repeatable = {});

  bool flag(const std::string& name) const { return flags_.count(name) > 0; }
  bool has(const std::string& name) const { return values_.count(name) > 0; }
  std::string get(const std::string& name, const std::string& fallback) const;
  std::string required(const std::string& name) const;
  std::vector<std::string> all(const std::string& name) const;
  double number(const std::string& name, double fallback) const;
  long integer(const std::string& name, long fallback) const;
  const std::vector<std::string>& positional() const { return positional_; }

 private:
  std::multimap<std::string, std::string> values_;
  std::set<std::string> flags_;
  std::vector<std::string> positional_;
};

// A subcommand: its name, a one-line summary, and the function that runs it (returns the exit
// code).
struct Command {
  std::string name;
  std::string summary;
  std::function<int(const std::vector<std::string>&)> run;
};

// Commands register themselves from their own translation units at start-up.
std::vector<Command>& commandRegistry();
struct RegisterCommand {
  explicit RegisterCommand(Command command) { commandRegistry().push_back(std::move(command)); }
};

}  // namespace robocal::cli
