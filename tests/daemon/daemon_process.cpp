#include "daemon_process.hpp"

#include <robocal/formats/error.hpp>

#include <sys/wait.h>
#include <unistd.h>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace robocal::test {

DaemonProcess::DaemonProcess(nlohmann::json config) : config_(std::move(config)) {
  char tmpl[] = "/tmp/robocald-test-XXXXXX";
  if (!::mkdtemp(tmpl)) throw std::runtime_error("mkdtemp failed");
  dir_ = tmpl;
  config_["data_dir"] = dataDir();
  config_["listen_address"] = "127.0.0.1";
  config_["port"] = 0;
  std::ofstream(dir_ + "/robocald.json") << config_.dump(1);
}

void DaemonProcess::keepPort() {
  config_["port"] = port_;
  std::ofstream(dir_ + "/robocald.json") << config_.dump(1);
}

DaemonProcess::~DaemonProcess() {
  stop();
  // ROBOCAL_KEEP_TEST_DIRS=1 keeps the daemon's folder (its log, runs) to look into a failure.
  if (const char* keep = std::getenv("ROBOCAL_KEEP_TEST_DIRS"); keep && *keep == '1') {
    std::fprintf(stderr, "kept %s\n", dir_.c_str());
    return;
  }
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

void DaemonProcess::start() {
  const std::string out = dir_ + "/stdout.txt";
  std::filesystem::remove(out);
  std::fflush(nullptr);  // the child must not inherit unwritten output
  pid_ = ::fork();
  if (pid_ == 0) {
    std::freopen(out.c_str(), "w", stdout);
    std::freopen((dir_ + "/stderr.txt").c_str(), "a", stderr);
    const std::string bin = ROBOCAL_BINARY_DIR "/daemon/robocald";
    const std::string cfg = dir_ + "/robocald.json";
    ::execl(bin.c_str(), bin.c_str(), "--config", cfg.c_str(), static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
  while (std::chrono::steady_clock::now() < deadline) {
    std::ifstream in(out);
    std::string word, address;
    unsigned port = 0;
    if (in >> word >> address >> port && word == "listening") {
      port_ = static_cast<unsigned short>(port);
      if (in >> word >> address >> port && word == "web")
        web_port_ = static_cast<unsigned short>(port);
      return;
    }
    if (!running()) throw std::runtime_error("robocald exited at start: " + logText());
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  throw std::runtime_error("robocald did not listen within 15 s: " + logText());
}

bool DaemonProcess::running() {
  if (pid_ <= 0) return false;
  int status = 0;
  if (::waitpid(pid_, &status, WNOHANG) == pid_) {
    pid_ = -1;
    return false;
  }
  return true;
}

void DaemonProcess::kill9() {
  if (pid_ <= 0) return;
  ::kill(pid_, SIGKILL);
  int status = 0;
  ::waitpid(pid_, &status, 0);
  pid_ = -1;
}

int DaemonProcess::stop() {
  if (pid_ <= 0) return -1;
  ::kill(pid_, SIGTERM);
  int status = 0;
  pid_t waited = 0;
  for (int i = 0; i < 500 && (waited = ::waitpid(pid_, &status, WNOHANG)) == 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  if (waited == 0) {
    kill9();
    return -1;
  }
  pid_ = -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string DaemonProcess::token() const {
  std::string t = readTextFile(dataDir() + "/token");
  while (!t.empty() && t.back() == '\n') t.pop_back();
  return t;
}

std::string DaemonProcess::logText() const {
  std::ifstream in(dir_ + "/stderr.txt");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::unique_ptr<proto::Client> DaemonProcess::client() const {
  return std::make_unique<proto::Client>("127.0.0.1", port_, 10.0);
}

nlohmann::json smallCell(const std::vector<std::string>& connections,
                         const std::vector<double>& extensions_mm, double lon_step_deg) {
  nlohmann::json cell = nlohmann::json::parse(readTextFile(ROBOCAL_SOURCE_DIR "/config/cell.json"));
  cell["connections"] = connections;
  cell["bar"]["extension_lengths_mm"] = extensions_mm;
  // Plain points: the tests that run the shipped cell's approach pre-points, revisits and
  // reference pose through robocald set them again (and keep the rest fast).
  cell["motion"]["approach_deg"] = 0;
  cell["motion"]["revisit_every"] = 0;
  cell["motion"]["reference_every_min"] = 0;
  cell["grid"] = {{"latitude_first_deg", 20.0},
                  {"latitude_last_deg", 80.0},
                  {"latitude_step_deg", 30.0},
                  {"longitude_first_deg", 0.0},
                  {"longitude_step_deg", lon_step_deg}};
  return cell;
}

std::optional<nlohmann::json> waitFor(proto::Client& client, const std::string& cls,
                                      double timeout_s, const std::string& state,
                                      std::vector<nlohmann::json>* seen) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    const double left =
        std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    auto obj = client.read(std::max(0.01, left));
    if (!obj) continue;
    if (seen) seen->push_back(*obj);
    if (obj->value("class", "") == cls && (state.empty() || obj->value("to", "") == state))
      return obj;
  }
  return std::nullopt;
}

}  // namespace robocal::test
