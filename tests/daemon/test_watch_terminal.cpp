// `robocal watch` as an operator sees it: in a real terminal (a pseudo-terminal, the screen
// rebuilt from the bytes as a terminal would draw them) and piped, attaching while a prompt waits
// and while the run measures.
#include <catch2/catch.hpp>

#include "sim_cell.hpp"

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <regex>

using namespace robocal;
using namespace robocal::test;
using json = nlohmann::json;
using Catch::Matchers::Contains;

namespace {

// A program on its own pseudo-terminal; what it wrote, drawn as a terminal draws it (carriage
// return, erase to the end of the line).
class TerminalProgram {
 public:
  explicit TerminalProgram(const std::vector<std::string>& argv) {
    struct winsize size = {30, 100, 0, 0};
    pid_ = ::forkpty(&master_, nullptr, nullptr, &size);
    REQUIRE(pid_ >= 0);
    if (pid_ == 0) {
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      ::execv(args[0], args.data());
      ::_exit(127);
    }
  }
  ~TerminalProgram() {
    if (pid_ > 0 && running()) ::kill(pid_, SIGTERM);
    if (pid_ > 0) ::waitpid(pid_, nullptr, 0);
    ::close(master_);
  }
  bool running() { return ::waitpid(pid_, nullptr, WNOHANG) == 0; }

  // Reads until the screen matches `pattern` or timeout_s pass; true when it matched.
  bool waitForScreen(const std::regex& pattern, double timeout_s) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < deadline) {
      if (std::regex_search(screen(), pattern)) return true;
      pollfd p{master_, POLLIN, 0};
      if (::poll(&p, 1, 100) > 0) {
        char buf[4096];
        const ssize_t n = ::read(master_, buf, sizeof buf);
        if (n <= 0) break;  // the program ended
        bytes_.append(buf, static_cast<std::size_t>(n));
      }
    }
    return std::regex_search(screen(), pattern);
  }

  std::string screen() const {
    std::vector<std::string> lines(1);
    std::size_t col = 0;
    for (std::size_t i = 0; i < bytes_.size(); ++i) {
      const char ch = bytes_[i];
      if (ch == '\r') {
        col = 0;
      } else if (ch == '\n') {
        lines.emplace_back();
        col = 0;
      } else if (ch == '\033' && bytes_.compare(i, 3, "\033[K") == 0) {
        lines.back().resize(std::min(col, lines.back().size()));
        i += 2;
      } else {
        std::string& l = lines.back();
        if (col < l.size())
          l[col] = ch;
        else
          l.push_back(ch);
        ++col;
      }
    }
    std::string out;
    for (const auto& l : lines) out += l + "\n";
    return out;
  }

 private:
  int master_ = -1;
  pid_t pid_ = -1;
  std::string bytes_;
};

}  // namespace

TEST_CASE("robocal watch in a terminal and piped, at a prompt and while measuring", "[watch]") {
  Cell cell({"B1C1"}, 23, true, 45);
  auto c = cell.daemon->client();
  c->send({{"cmd", "watch"}, {"enable", true}});
  REQUIRE(c->request({{"cmd", "start"}, {"token", cell.daemon->token()}}, 30, "ACK")["class"] ==
          "ACK");
  const auto prompt = waitFor(*c, "PROMPT", 60);
  REQUIRE(prompt);
  const std::string port = std::to_string(cell.daemon->port());

  // Piped, attached while the prompt waits: the prompt is shown, with the command to type.
  const auto piped = runRobocal("watch --port " + port + " --timeout-s 2");
  INFO(piped.output);
  CHECK(piped.exit_code == 3);  // its timeout, not a crash
  CHECK_THAT(piped.output, Contains("state: awaiting_confirm"));
  CHECK_THAT(piped.output, Contains("Connect ball 1 to chuck 1 without extension."));
  CHECK_THAT(piped.output, Contains("robocal confirm --shell 1"));
  CHECK_THAT(piped.output, !Contains("\033"));  // no terminal codes in a pipe

  // In a terminal: the same prompt, then the live line while the run measures.
  TerminalProgram watch({binDir() + "/robocal", "watch", "--port", port});
  CHECK(watch.waitForScreen(std::regex("OPERATOR: CONNECT THE BALL-BAR"), 10));
  CHECK(watch.waitForScreen(std::regex("Then type: +robocal confirm --shell 1"), 10));
  // The live line at the first prompt names the shell to come, never a shell 0.
  CHECK(watch.waitForScreen(std::regex("shell 1/1"), 10));
  CHECK(watch.screen().find("shell 0/") == std::string::npos);
  sim::answerPrompt(
      *c, proto::parseObject<proto::Prompt>(*prompt),
      [&](const std::string& cmd) { return cell.sim->control(cmd); }, cell.daemon->token(), 150);
  const std::regex live(
      R"(\n\[[#.]{20}\] [1-9][0-9]*/[0-9]+  shell 1/1 B1C1  left [0-9]+:[0-9]{2}:[0-9]{2}  bar [+-][0-9]\.[0-9]{3} mm\n$)");
  const bool measuring = watch.waitForScreen(std::regex("state: measuring - shell 1 B1C1"), 30);
  const bool live_line = watch.waitForScreen(live, 30);
  INFO(watch.screen());
  INFO(c->request({{"cmd", "status"}}, 10, "STATUS").dump());
  CHECK(measuring);
  CHECK(live_line);
  CHECK(watch.running());
  REQUIRE(c->request({{"cmd", "abort"}, {"token", cell.daemon->token()}}, 10, "ACK")["class"] ==
          "ACK");
  CHECK(watch.waitForScreen(std::regex("state: aborted"), 30));
  CHECK(watch.running());
}

TEST_CASE("robocal watch says when robocald goes away and watches again once it is back",
          "[watch]") {
  Cell cell({"B1C1"}, 23, true, 45);
  cell.daemon->keepPort();
  const std::string port = std::to_string(cell.daemon->port());
  TerminalProgram watch({binDir() + "/robocal", "watch", "--port", port, "--timeout-s", "60"});
  REQUIRE(watch.waitForScreen(std::regex("state: idle"), 10));
  // Idle: the live line says there is no run, not "0/0 shell 0/0".
  CHECK(watch.waitForScreen(std::regex("no run in progress  bar [+-][0-9]\\.[0-9]{3} mm"), 10));
  CHECK_FALSE(std::regex_search(watch.screen(), std::regex("0/0")));
  REQUIRE(cell.daemon->stop() == 0);
  INFO(watch.screen());
  CHECK(watch.waitForScreen(
      std::regex("\nrobocald closed the connection[^\n]*\nreconnecting every 2 s"), 10));
  cell.daemon->start();
  CHECK(watch.waitForScreen(std::regex("reconnected to robocald\n(.*\n)*state: idle"), 20));
  CHECK(watch.running());
}
