// robocal: the command line. Each subcommand lives in its own cmd_*.cpp and registers itself.
#include "args.hpp"

#include <robocal/build_info.hpp>
#include <robocal/formats/error.hpp>

#include <algorithm>
#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  using robocal::cli::commandRegistry;
  auto& commands = commandRegistry();
  std::sort(commands.begin(), commands.end(),
            [](const auto& a, const auto& b) { return a.name < b.name; });
  const std::string name = argc > 1 ? argv[1] : "";
  if (name.empty() || name == "help" || name == "--help" || name == "-h") {
    std::printf(
        "usage: robocal <command> [options]   (robocal <command> --help for its options)\n"
        "       robocal --version\n\n");
    for (const auto& c : commands) std::printf("  %-14s %s\n", c.name.c_str(), c.summary.c_str());
    return name.empty() ? 2 : 0;
  }
  if (name == "--version") {
    std::printf("robocal %s\n", robocal::build::kVersion);
    return 0;
  }
  for (const auto& c : commands) {
    if (c.name != name) continue;
    try {
      return c.run(std::vector<std::string>(argv + 2, argv + argc));
    } catch (const robocal::cli::UsageError& e) {
      std::fprintf(stderr, "robocal %s: %s (see robocal %s --help)\n", name.c_str(), e.what(),
                   name.c_str());
      return 2;
    } catch (const robocal::FormatError& e) {
      std::fprintf(stderr, "robocal %s: %s\n", name.c_str(), e.what());
      return 1;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "robocal %s: error: %s\n", name.c_str(), e.what());
      return 1;
    }
  }
  std::fprintf(stderr, "robocal: unknown command '%s' (robocal help lists them)\n", name.c_str());
  return 2;
}
