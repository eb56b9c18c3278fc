// Test helper: robocald as a child process on a free loopback port, with a config written for
// the test (its drivers pointed at a robocal-cellsim's pty links), in a private folder that
// survives restarts (for the crash tests). Clients talk to it over real TCP.
#pragma once

#include <robocal/proto/client.hpp>

#include <nlohmann/json.hpp>

#include <memory>
#include <string>

namespace robocal::test {

class DaemonProcess {
 public:
  // `config` is robocald's config; data_dir, listen_address and port are filled in.
  explicit DaemonProcess(nlohmann::json config);
  ~DaemonProcess();
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;

  void start();  // runs robocald and waits until it listens
  // The next start listens on the port this one got (a client that reconnects finds it).
  void keepPort();
  void kill9();  // SIGKILL, as a crash or power loss would
  int stop();    // SIGTERM and wait: the exit code (128 + signal when killed by one, -1 if hung)
  bool running();
  unsigned short port() const { return port_; }
  unsigned short webPort() const { return web_port_; }  // 0 without web_port in the config
  const std::string& dir() const { return dir_; }
  std::string dataDir() const { return dir_ + "/data"; }
  std::string token() const;
  std::string logText() const;
  std::unique_ptr<proto::Client> client() const;

 private:
  nlohmann::json config_;
  std::string dir_;
  int pid_ = -1;
  unsigned short port_ = 0;
  unsigned short web_port_ = 0;
};

// A small cell for tests: three or more connections on a coarse grid.
nlohmann::json smallCell(const std::vector<std::string>& connections,
                         const std::vector<double>& extensions_mm, double lon_step_deg = 60);

// Reads objects until one of class `cls` (and, when given, with "to" == `state`) arrives;
// nullopt after timeout_s. Every object read is appended to `seen` when given.
std::optional<nlohmann::json> waitFor(proto::Client& client, const std::string& cls,
                                      double timeout_s, const std::string& state = {},
                                      std::vector<nlohmann::json>* seen = nullptr);

}  // namespace robocal::test
