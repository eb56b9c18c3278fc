#include "cellsim_process.hpp"

#include <robocal/drivers/errors.hpp>

#include <nlohmann/json.hpp>

#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace robocal::test {
namespace {

std::string cellsimBinary() {
  return ROBOCAL_BINARY_DIR "/sim/cellsim/robocal-cellsim";
}

int connectControl(const std::string& path) {
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

}  // namespace

CellSimProcess::CellSimProcess(const std::vector<std::string>& args, const std::string& config_json)
    : config_json_(config_json) {
  if (::access(cellsimBinary().c_str(), X_OK) != 0)
    throw std::runtime_error(cellsimBinary() + " is missing: build the robocal-cellsim target");
  char tmpl[] = "/tmp/robocal-cellsim-XXXXXX";
  if (!::mkdtemp(tmpl)) throw std::runtime_error("mkdtemp failed");
  dir_ = tmpl;
  std::vector<std::string> argv = {
      cellsimBinary(), "--model",   ROBOCAL_SOURCE_DIR "/config/puma560-paper.json",
      "--val-link",    valPath(),   "--bar-link",
      barPath(),       "--control", dir_ + "/control"};
  if (!config_json.empty()) {
    std::ofstream(dir_ + "/drivers.json") << config_json;
    argv.push_back("--config");
    argv.push_back(dir_ + "/drivers.json");
  }
  argv.insert(argv.end(), args.begin(), args.end());
  const std::string out = dir_ + "/stdout.txt", err = dir_ + "/stderr.txt";
  std::fflush(nullptr);  // the child must not inherit unwritten output
  pid_ = ::fork();
  if (pid_ == 0) {
    std::freopen(out.c_str(), "w", stdout);
    std::freopen(err.c_str(), "w", stderr);
    std::vector<char*> cargv;
    for (auto& a : argv) cargv.push_back(a.data());
    cargv.push_back(nullptr);
    ::execv(cargv[0], cargv.data());
    std::_Exit(127);
  }
  // Ready when the control socket answers and both links exist.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < deadline) {
    struct stat st {};
    const int fd = connectControl(dir_ + "/control");
    if (fd >= 0) {
      ::close(fd);
      if (::stat(valPath().c_str(), &st) == 0 && ::stat(barPath().c_str(), &st) == 0) return;
    }
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      throw std::runtime_error("robocal-cellsim exited at start: " + stderrText());
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  throw std::runtime_error("robocal-cellsim did not start within 10 s: " + stderrText());
}

CellSimProcess::~CellSimProcess() {
  if (pid_ > 0) {
    ::kill(pid_, SIGTERM);
    int status = 0;
    for (int i = 0; i < 300 && ::waitpid(pid_, &status, WNOHANG) == 0; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    if (::waitpid(pid_, &status, WNOHANG) == 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status, 0);
    }
  }
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

std::string CellSimProcess::stderrText() const {
  std::ifstream in(dir_ + "/stderr.txt");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string CellSimProcess::control(const std::string& command) const {
  const int fd = connectControl(dir_ + "/control");
  if (fd < 0) throw std::runtime_error("cannot reach the cellsim control socket");
  const std::string line = command + "\n";
  if (::write(fd, line.data(), line.size()) != static_cast<ssize_t>(line.size())) {
    ::close(fd);
    throw std::runtime_error("cannot write to the cellsim control socket");
  }
  std::string reply;
  char c;
  while (::read(fd, &c, 1) == 1 && c != '\n') reply.push_back(c);
  ::close(fd);
  return reply;
}

std::string CellSimProcess::status(const std::string& key) const {
  std::istringstream in(control("status"));
  for (std::string word; in >> word;)
    if (word.rfind(key + "=", 0) == 0) return word.substr(key.size() + 1);
  return "";
}

double maxJointDiff(const drivers::Joints6& a, const drivers::Joints6& b) {
  return drivers::maxJointDiffDeg(a, b);
}

std::pair<int, std::string> runShell(const std::string& command) {
  FILE* p = ::popen((command + " 2>&1").c_str(), "r");
  if (!p) return {-1, "cannot run " + command};
  std::string out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  const int status = ::pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

drivers::DriversConfig CellSimProcess::driversConfig() const {
  drivers::DriversConfig c;
  if (!config_json_.empty())
    c = drivers::driversConfigFromJson(nlohmann::json::parse(config_json_), "test config");
  c.val.serial.path = valPath();
  c.bar.serial.path = barPath();
  c.val.poll_interval_s = 0.03;
  c.val.motion_timeout_s = 20;
  return c;
}

}  // namespace robocal::test
