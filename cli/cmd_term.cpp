// robocal term: a minimal line terminal to the VAL II controller, for a cell's first day. Sends
// each line typed on stdin with the configured line ending, shows every byte the controller sends
// as it arrives, and with --record writes the session as a test transcript
// (robocal/drivers/transcript.hpp) so a real controller's dialect becomes a test case. It never
// sends anything the user did not type.
#include "args.hpp"
#include "device_args.hpp"

#include <robocal/build_info.hpp>
#include <robocal/drivers/config.hpp>
#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/transcript.hpp>
#include <robocal/drivers/transport.hpp>
#include <robocal/formats/error.hpp>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/write.hpp>

#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <thread>

namespace robocal::cli {
namespace {

constexpr const char* kHelp = R"(usage: robocal term [--val PORT] [--record FILE] [options]

A line terminal to the VAL II controller, for a cell's first day: each line typed is sent with
the configured line ending (val.send_line_ending), and every byte the controller sends is shown
as it arrives (line endings as new lines, other control bytes escaped as \xNN). Nothing is sent
that was not typed. Ends at end of input (Ctrl-D; the last reply is waited for), at a line "~.",
or on Ctrl-C.

With --record FILE, the session is written to FILE as a test transcript
(tests/drivers/transcripts/README.md): rewritten after each reply, and at the end. Copy it to
tests/drivers/transcripts/ and add the expectations under its "# TODO expectation" lines
(docs/drivers.md, "First day at a real controller").

PORT is a device path (/dev/ttyUSB0, /dev/serial/by-id/..., a pty), "usb-serial:NUMBER" or
"usb:TEXT" (see robocal ports). Without --val: val.serial of the config file.

The config file is a drivers config (config/drivers.json) or robocald's own config file, whose
"drivers" section is read as the daemon reads it. Without --config: config/drivers.json if
present, else the daemon's %s if present, else the defaults.

  --val PORT            the controller's port
  --config FILE         drivers or robocald config (port, baud rate, dialect)
  --val-baud N          override val.serial.baud
  --record FILE         write the session as a test transcript
  --wait S              when the input is not a terminal, wait up to S seconds for the prompt
                        before sending the next line                     [10]
)";

std::string localTime() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  ::localtime_r(&now, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M:%S %z", &tm);
  return buf;
}

// Reads stdin in its own thread (a terminal, a pipe or a file alike) and posts each line, without
// its line ending, to the io_context; then nullopt at end of input. Stops when destroyed.
class StdinLines {
 public:
  using Handler = std::function<void(std::optional<std::string>)>;
  StdinLines(boost::asio::io_context& io, Handler handler) : io_(io), handler_(std::move(handler)) {
    if (::pipe(stop_) != 0) throw std::runtime_error("pipe failed");
    thread_ = std::thread([this] { loop(); });
  }
  ~StdinLines() {
    const char c = 0;
    [[maybe_unused]] const ssize_t n = ::write(stop_[1], &c, 1);
    thread_.join();
    ::close(stop_[0]);
    ::close(stop_[1]);
  }

 private:
  void post(std::optional<std::string> line) {
    boost::asio::post(io_, [h = handler_, line = std::move(line)] { h(line); });
  }
  void loop() {
    std::string partial;
    char buf[4096];
    for (;;) {
      pollfd fds[2] = {{STDIN_FILENO, POLLIN, 0}, {stop_[0], POLLIN, 0}};
      if (::poll(fds, 2, -1) < 0) {
        if (errno == EINTR) continue;
        break;
      }
      if (fds[1].revents) return;
      const ssize_t n = ::read(STDIN_FILENO, buf, sizeof buf);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      partial.append(buf, static_cast<std::size_t>(n));
      for (std::size_t eol; (eol = partial.find('\n')) != std::string::npos;) {
        std::string line = partial.substr(0, eol);
        partial.erase(0, eol + 1);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        post(std::move(line));
      }
    }
    if (!partial.empty()) post(std::move(partial));
    post(std::nullopt);
  }

  boost::asio::io_context& io_;
  Handler handler_;
  int stop_[2] = {-1, -1};
  std::thread thread_;
};

class Session {
 public:
  Session(boost::asio::io_context& io, drivers::SerialLink& link, const drivers::ValConfig& val,
          std::vector<std::string> header, std::string record_path, double wait_s)
      : io_(io),
        link_(link),
        line_ending_(val.send_line_ending),
        recorder_(val, std::move(header)),
        record_path_(std::move(record_path)),
        wait_s_(wait_s),
        pace_(!::isatty(STDIN_FILENO)),
        timer_(io) {}

  // Runs until the end of the session; returns the exit code.
  int run() {
    saveRecord();
    if (done_) return exit_code_;
    link_.receive([this](std::string_view bytes) { onBytes(bytes); },
                  [this](const std::string& why) { fail(link_.disconnected(why).what()); });
    boost::asio::signal_set signals(io_, SIGINT, SIGTERM);
    signals.async_wait([this](const boost::system::error_code& ec, int) {
      if (!ec) finish();
    });
    auto guard = boost::asio::make_work_guard(io_);
    {
      StdinLines input(io_, [this](std::optional<std::string> line) { onLine(std::move(line)); });
      while (!done_) io_.run_one();
    }
    signals.cancel();
    if (line_open_) std::printf("\n");  // after the last prompt
    if (!record_path_.empty() && exit_code_ == 0) {
      const int bad = recorder_.unreplayableExchanges();
      std::fprintf(stderr, "robocal term: recorded %d exchange(s) to %s",
                   recorder_.replayableExchanges(), record_path_.c_str());
      if (bad > 0)
        std::fprintf(stderr, " and %d not replayable (commented out, with the reason)", bad);
      std::fprintf(stderr, "\n");
    }
    return exit_code_;
  }

 private:
  void onLine(std::optional<std::string> line) {
    if (done_) return;
    if (line)
      queue_.push_back(std::move(*line));
    else
      eof_ = true;
    pump();
  }

  // Sends the typed lines in order: at once from a terminal (a person paces them), else each
  // after the previous reply's prompt (or --wait seconds). A line "~." ends the session where it
  // comes; the end of input, after the last reply.
  void pump() {
    while (!done_ && !queue_.empty()) {
      if (pace_ && recorder_.awaitingReply() && !waited_) return;
      const std::string line = std::move(queue_.front());
      queue_.pop_front();
      if (line == "~.") {
        finish();
        return;
      }
      send(line);
    }
    if (!done_ && eof_ && queue_.empty() && (!recorder_.awaitingReply() || waited_)) finish();
  }

  void send(const std::string& line) {
    recorder_.command(line);
    outbox_ += line + line_ending_;
    flush();
    waited_ = false;
    timer_.expires_after(std::chrono::duration_cast<drivers::Clock::duration>(
        std::chrono::duration<double>(wait_s_)));
    timer_.async_wait([this](const boost::system::error_code& ec) {
      if (ec || done_) return;
      waited_ = true;
      pump();
    });
    saveRecord();
  }

  void flush() {
    if (writing_ || outbox_.empty() || !link_.isOpen()) return;
    writing_ = true;
    auto bytes = std::make_shared<std::string>(std::move(outbox_));
    outbox_.clear();
    boost::asio::async_write(link_.stream(), boost::asio::buffer(*bytes),
                             [this, bytes](const boost::system::error_code& ec, std::size_t) {
                               writing_ = false;
                               if (done_) return;
                               if (ec) {
                                 fail(link_.disconnected(ec.message()).what());
                                 return;
                               }
                               flush();
                             });
  }

  void onBytes(std::string_view bytes) {
    if (done_) return;
    const std::string shown = screen_.feed(bytes);
    std::fwrite(shown.data(), 1, shown.size(), stdout);
    std::fflush(stdout);
    if (!shown.empty()) line_open_ = shown.back() != '\n';
    const bool awaiting = recorder_.awaitingReply();
    recorder_.received(bytes);
    if (awaiting && !recorder_.awaitingReply()) {
      saveRecord();
      pump();
    }
  }

  void saveRecord() {
    if (record_path_.empty()) return;
    try {
      writeTextFileAtomic(record_path_, recorder_.text());
    } catch (const FormatError& e) {
      // Said here rather than by fail(): finish() saves too, after done_ is set.
      if (!record_failed_)
        std::fprintf(stderr, "\nrobocal term: cannot write the record file %s: %s\n",
                     record_path_.c_str(), e.what());
      record_failed_ = true;
      exit_code_ = 1;
      finish();
    }
  }

  void fail(const std::string& message) {
    if (done_) return;
    std::fprintf(stderr, "\nrobocal term: %s\n", message.c_str());
    exit_code_ = 1;
    finish();
  }

  void finish() {
    if (done_) return;
    done_ = true;
    timer_.cancel();
    link_.close();
    saveRecord();
  }

  boost::asio::io_context& io_;
  drivers::SerialLink& link_;
  std::string line_ending_;
  drivers::TranscriptRecorder recorder_;
  drivers::ScreenText screen_;
  std::string record_path_;
  double wait_s_;
  bool pace_;
  boost::asio::steady_timer timer_;
  std::deque<std::string> queue_;
  std::string outbox_;
  bool writing_ = false, waited_ = false, eof_ = false, done_ = false, record_failed_ = false,
       line_open_ = false;
  int exit_code_ = 0;
};

int run(const std::vector<std::string>& argv) {
  const Args args(argv, {"val", "config", "val-baud", "record", "wait"}, {"help"});
  if (args.flag("help")) {
    std::printf(kHelp, build::kDaemonConfigFile);
    return 0;
  }
  if (!args.positional().empty())
    throw UsageError("unexpected argument '" + args.positional().front() + "'");
  const std::string config_file = findDriversConfig(args.get("config", ""));
  drivers::DriversConfig config = loadDevicesConfig(config_file);
  if (args.has("val")) applyPort(config.val.serial, args.get("val", ""));
  config.val.serial.baud = static_cast<int>(args.integer("val-baud", config.val.serial.baud));
  const double wait_s = args.number("wait", 10);
  if (wait_s <= 0 || wait_s > 3600) throw UsageError("--wait must be above 0 and at most 3600");
  const std::string record = args.get("record", "");
  if (args.has("record") && record.empty()) throw UsageError("--record needs a file name");
  try {
    drivers::validate(config.val);
  } catch (const drivers::ConfigError& e) {
    throw UsageError(e.what());
  }

  boost::asio::io_context io;
  drivers::SerialLink link(io, config.val.serial);
  link.open();  // PortError naming the port
  const auto& s = config.val.serial;
  const std::string port = link.describe() + " (" + link.opener() + "), " + std::to_string(s.baud) +
                           " baud, " + std::to_string(s.data_bits) + " data bits, parity " +
                           s.parity + ", " + std::to_string(s.stop_bits) +
                           " stop bit(s), flow control " + s.flow_control;
  std::vector<std::string> header = {
      "Recorded by robocal term " + std::string(build::kVersion) + " on " + localTime(),
      "port: " + port, "config: " + (config_file.empty() ? std::string("defaults") : config_file)};
  std::fprintf(stderr,
               "robocal term: connected to %s; type commands, end with Ctrl-D or a line ~.%s%s\n",
               port.c_str(), record.empty() ? "" : "; recording to ", record.c_str());
  Session session(io, link, config.val, std::move(header), record, wait_s);
  return session.run();
}

const RegisterCommand registered({"term",
                                  "a line terminal to the controller, recording a test transcript",
                                  run});

}  // namespace
}  // namespace robocal::cli
