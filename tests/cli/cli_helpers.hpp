// Runs the real robocal executable (as a user would), or another program, and captures its
// output; a temporary directory per test.
#pragma once

#include <sys/wait.h>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace robocal::test {

inline std::string binDir() {
  const char* env = std::getenv("ROBOCAL_BIN");
  return env ? env : ROBOCAL_BINARY_DIR "/cli";
}

struct RunResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

// Runs a shell command line and captures what it prints (as the command line redirects it).
inline RunResult runCommand(const std::string& cmd) {
  RunResult r;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// `stderr_too`: the output has stderr after stdout's lines (false: stdout alone, e.g. a --json
// object followed by the problems a failing command lists on stderr).
inline RunResult runRobocal(const std::string& args, bool stderr_too = true) {
  return runCommand(binDir() + "/robocal " + args + (stderr_too ? " 2>&1" : " 2>/dev/null"));
}

// A fresh temporary directory for one test, removed at the end.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    char tmpl[] = "/tmp/robocal-test-XXXXXX";
    path = ::mkdtemp(tmpl);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
  std::string operator/(const std::string& name) const { return (path / name).string(); }
};

inline const std::string kModel = ROBOCAL_SOURCE_DIR "/config/puma560-paper.json";

}  // namespace robocal::test
