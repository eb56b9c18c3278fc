// Test helper: runs robocal-cellsim as a child process on real pseudo-terminals, in a private
// temporary folder, and talks to its control socket. The drivers under test open the pty links
// exactly as they would open a real port; nothing stands in for the serial link.
#pragma once

#include <robocal/drivers/config.hpp>
#include <robocal/drivers/protocol.hpp>

#include <string>
#include <utility>
#include <vector>

namespace robocal::test {

// The joints cellsim starts at (deg), and the largest difference between two joint sets (deg).
inline const drivers::Joints6 kCellSimStart{0, 45, -90, 0, 45, 0};
double maxJointDiff(const drivers::Joints6& a, const drivers::Joints6& b);

// Runs a shell command line; its exit code and its stdout and stderr.
std::pair<int, std::string> runShell(const std::string& command);

class CellSimProcess {
 public:
  // `args` are added to: --model (the nominal PUMA) --val-link --bar-link --control.
  // `config_json` (when not empty) is written to a file and passed as --config.
  explicit CellSimProcess(const std::vector<std::string>& args = {},
                          const std::string& config_json = "");
  ~CellSimProcess();
  CellSimProcess(const CellSimProcess&) = delete;
  CellSimProcess& operator=(const CellSimProcess&) = delete;

  std::string valPath() const { return dir_ + "/val"; }
  std::string barPath() const { return dir_ + "/bar"; }
  const std::string& dir() const { return dir_; }
  // One control command and its reply line ("ok ..." or "error: ...").
  std::string control(const std::string& command) const;
  // The value of key=value in the status reply.
  std::string status(const std::string& key) const;
  // The config given to the simulator (or the defaults), pointed at the pty links, with the
  // generous test timeouts.
  drivers::DriversConfig driversConfig() const;
  std::string stderrText() const;

 private:
  std::string dir_, config_json_;
  int pid_ = -1;
};

}  // namespace robocal::test
