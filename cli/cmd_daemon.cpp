// robocal as the operator's client of robocald: status, watch, start, confirm, pause, resume,
// abort, result, runs. Plain `nc localhost 7687` works too: the protocol is JSON lines.
#include "args.hpp"

#include <robocal/formats/error.hpp>
#include <robocal/proto/client.hpp>
#include <robocal/proto/sim_operator.hpp>

#include <boost/asio/io_context.hpp>
#include <boost/asio/local/stream_protocol.hpp>
#include <boost/asio/read_until.hpp>
#include <boost/asio/streambuf.hpp>
#include <boost/asio/write.hpp>

#include <unistd.h>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <set>

namespace robocal::cli {
namespace {

using json = nlohmann::json;

constexpr const char* kCommon = R"(
  --host H             robocald's address                           [127.0.0.1]
  --port N             robocald's port                              [7687]
  --token-file FILE    the token (commands that move the robot)     [$ROBOCAL_TOKEN_FILE or
                                                                     /var/lib/robocald/token]
  --json               print the daemon's JSON objects as they are
)";

const std::set<std::string> kCommonValued = {"host", "port", "token-file"};

std::set<std::string> valued(std::set<std::string> more) {
  more.insert(kCommonValued.begin(), kCommonValued.end());
  return more;
}

std::unique_ptr<proto::Client> connectTo(const Args& args) {
  const long port = args.integer("port", 7687);
  if (port < 1 || port > 65535) throw UsageError("--port must be 1 to 65535");
  return std::make_unique<proto::Client>(args.get("host", "127.0.0.1"),
                                         static_cast<unsigned short>(port));
}

std::string token(const Args& args) {
  const char* env = std::getenv("ROBOCAL_TOKEN_FILE");
  const std::string path = args.get("token-file", env ? env : "/var/lib/robocald/token");
  std::string t = readTextFile(path);
  while (!t.empty() && (t.back() == '\n' || t.back() == '\r')) t.pop_back();
  return t;
}

// Prints a reply; returns the exit code (1 for ERROR).
int show(const json& reply, bool as_json) {
  if (as_json) {
    std::printf("%s\n", reply.dump().c_str());
  } else if (reply.value("class", "") == "ERROR") {
    std::fprintf(stderr, "robocald: %s\n", reply.value("message", "?").c_str());
    if (reply.contains("violations"))
      for (const auto& v : reply["violations"])
        std::fprintf(stderr, "  %s\n", v.get<std::string>().c_str());
  } else if (reply.value("class", "") == "ACK") {
    std::printf("ok: %s%s%s\n", reply.value("cmd", "").c_str(),
                reply.contains("message") ? ": " : "", reply.value("message", "").c_str());
  } else {
    std::printf("%s\n", reply.dump(2).c_str());
  }
  return reply.value("class", "") == "ERROR" ? 1 : 0;
}

std::string duration(double s) {
  char buf[32];
  const long t = static_cast<long>(s + 0.5);
  std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  return buf;
}

void printStatus(const json& s) {
  std::printf("state: %s%s%s\n", s.value("state", "?").c_str(),
              s.value("reason", "").empty() ? "" : " - ", s.value("reason", "").c_str());
  if (!s.value("run", "").empty())
    std::printf("run: %s   shell %d of %d   points %d of %d   time left %s\n",
                s.value("run", "").c_str(), s.value("shell", 0), s.value("shells", 0),
                s.value("points_done", 0), s.value("points_total", 0),
                duration(s.value("eta_s", 0.0)).c_str());
  if (s.contains("resumable"))
    std::printf("resumable run: %s\n", s["resumable"].get<std::string>().c_str());
  if (s.contains("devices"))
    std::printf("devices: VAL II %s, ball-bar %s\n",
                s["devices"].value("val", false) ? "connected" : "not connected",
                s["devices"].value("bar", false) ? "connected" : "not connected");
  if (s.contains("bar") && s["bar"].contains("deflection_mm"))
    std::printf("bar: %+.4f mm deflection\n", s["bar"]["deflection_mm"].get<double>());
  if (s.contains("prompt"))
    std::printf("\n*** OPERATOR: %s ***\n", s["prompt"].value("message", "").c_str());
}

// The simulated operator: tells robocal-cellsim to move the bar, as a person would.
std::string cellsimControl(const std::string& socket_path, const std::string& command) {
  boost::asio::io_context io;
  boost::asio::local::stream_protocol::socket s(io);
  s.connect(boost::asio::local::stream_protocol::endpoint(socket_path));
  boost::asio::write(s, boost::asio::buffer(command + "\n"));
  boost::asio::streambuf buf;
  boost::asio::read_until(s, buf, '\n');
  std::string reply(boost::asio::buffers_begin(buf.data()), boost::asio::buffers_end(buf.data()));
  while (!reply.empty() && reply.back() == '\n') reply.pop_back();
  return reply;
}

int simple(const std::vector<std::string>& argv, const char* cmd, bool with_token,
           const std::set<std::string>& extra, const std::function<void(const Args&, json&)>& fill,
           const char* help) {
  const Args args(argv, valued(extra), {"json", "help"});
  if (args.flag("help")) {
    std::printf("%s%s", help, kCommon);
    return 0;
  }
  json req = {{"cmd", cmd}};
  if (with_token) req["token"] = token(args);
  if (fill) fill(args, req);
  auto client = connectTo(args);
  const json reply = client->request(req, 30.0);
  if (!args.flag("json") && reply.value("class", "") == "STATUS") {
    printStatus(reply);
    return 0;
  }
  return show(reply, args.flag("json"));
}

int status(const std::vector<std::string>& argv) {
  return simple(argv, "status", false, {}, {}, "usage: robocal status [options]\n");
}
int result(const std::vector<std::string>& argv) {
  return simple(argv, "result", false, {}, {}, "usage: robocal result [options]\n");
}
int runs(const std::vector<std::string>& argv) {
  return simple(argv, "runs", false, {}, {}, "usage: robocal runs [options]\n");
}
int start(const std::vector<std::string>& argv) {
  return simple(
      argv, "start", true, {},
      [](const Args& a, json& r) {
        if (a.positional().size() > 1) throw UsageError("one plan file at most");
        if (!a.positional().empty()) r["plan"] = a.positional()[0];
      },
      "usage: robocal start [PLAN.json] [options]\n  Starts a calibration run (with the daemon's "
      "plan, or PLAN.json as robocald sees the path).\n");
}
int confirm(const std::vector<std::string>& argv) {
  return simple(
      argv, "confirm", true, {"shell"},
      [](const Args& a, json& r) {
        if (a.has("shell")) r["shell"] = a.integer("shell", 0);
      },
      "usage: robocal confirm [--shell N] [options]\n  Tells robocald the bar is connected (or "
      "detached) as the prompt asked.\n");
}
int nudge(const std::vector<std::string>& argv) {
  return simple(
      argv, "nudge", true, {"mm", "shell"},
      [](const Args& a, json& r) {
        if (!a.has("mm")) throw UsageError("--mm is required");
        r["mm"] = a.number("mm", 0);
        if (a.has("shell")) r["shell"] = a.integer("shell", 0);
      },
      "usage: robocal nudge --mm D [--shell N] [options]\n  While a connect prompt waits: moves "
      "the ball D mm along the bar's line (+ away from the\n  chuck) so the bar can be seated.\n");
}
int pause(const std::vector<std::string>& argv) {
  return simple(
      argv, "pause", true, {"reason"},
      [](const Args& a, json& r) { r["reason"] = a.get("reason", ""); },
      "usage: robocal pause [--reason TEXT] [options]\n");
}
int resume(const std::vector<std::string>& argv) {
  return simple(
      argv, "resume", true, {"run"},
      [](const Args& a, json& r) {
        if (a.has("run")) r["run"] = a.get("run", "");
      },
      "usage: robocal resume [--run ID] [options]\n");
}
int abortRun(const std::vector<std::string>& argv) {
  return simple(
      argv, "abort", true, {"reason"},
      [](const Args& a, json& r) { r["reason"] = a.get("reason", ""); },
      "usage: robocal abort [--reason TEXT] [options]\n  Stops the robot now and ends the run.\n");
}

constexpr const char* kWatchHelp = R"(usage: robocal watch [options]

Streams the live bar reading, the run's progress and the operator's prompts until interrupted.
  --until STATES           exit when the run reaches one of these (comma list, e.g. done,paused)
  --timeout-s S            give up after S seconds (exit 3)
  --operator-cellsim SOCK  act as the operator of a simulated cell: answer each prompt by telling
                           robocal-cellsim (control socket SOCK) to move the bar, then confirm
  --bar-mm L               with --operator-cellsim: the bar's length without extension    [150]
)";

int watch(const std::vector<std::string>& argv) {
  const Args args(argv, valued({"until", "timeout-s", "operator-cellsim", "bar-mm"}),
                  {"json", "help"});
  if (args.flag("help")) {
    std::printf("%s%s", kWatchHelp, kCommon);
    return 0;
  }
  std::set<std::string> until;
  {
    const std::string list = args.get("until", "");
    size_t start = 0;
    while (start < list.size()) {
      size_t comma = list.find(',', start);
      if (comma == std::string::npos) comma = list.size();
      until.insert(list.substr(start, comma - start));
      start = comma + 1;
    }
  }
  const double timeout_s = args.number("timeout-s", 0);
  const std::string operator_socket = args.get("operator-cellsim", "");
  const double bar_mm = args.number("bar-mm", 150);
  const std::string tok = operator_socket.empty() ? "" : token(args);
  const bool as_json = args.flag("json");
  const bool tty = ::isatty(STDOUT_FILENO);

  auto client = connectTo(args);
  client->send({{"cmd", "watch"}, {"enable", true}});
  const auto started = std::chrono::steady_clock::now();
  double last_bar = 0;
  bool have_bar = false;
  json progress;
  int exit_code = 0;
  while (true) {
    if (timeout_s > 0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count() >
            timeout_s) {
      std::fprintf(stderr, "robocal watch: timed out after %.0f s\n", timeout_s);
      return 3;
    }
    auto obj = client->read(0.5);
    if (!obj) continue;
    const std::string cls = obj->value("class", "");
    if (as_json && cls != "BAR") std::printf("%s\n", obj->dump().c_str());
    if (cls == "BAR") {
      if (as_json) {
        std::printf("%s\n", obj->dump().c_str());
      } else if (obj->contains("deflection_mm")) {
        last_bar = (*obj)["deflection_mm"].get<double>();
        have_bar = true;
      }
    } else if (cls == "PROGRESS") {
      progress = *obj;
    } else if (cls == "STATE" && !as_json) {
      std::printf("%sstate: %s%s%s\n", tty ? "\r\033[K" : "", obj->value("to", "").c_str(),
                  obj->contains("reason") ? " - " : "", obj->value("reason", "").c_str());
    } else if (cls == "PROMPT") {
      if (!as_json)
        std::printf("%s\n*** OPERATOR: %s ***\n\n", tty ? "\r\033[K" : "",
                    obj->value("message", "").c_str());
      if (!operator_socket.empty() && obj->value("shell", 0) > 0) {
        const auto control = [&](const std::string& c) {
          return cellsimControl(operator_socket, c);
        };
        for (const std::string& action : proto::answerPrompt(*client, *obj, control, tok, bar_mm))
          if (!as_json) std::printf("(simulated operator: %s)\n", action.c_str());
      }
    } else if (cls == "RESULT" && !as_json) {
      std::printf("%s\nRESULT set %d: %zu samples, rank %d, RMS %.4f mm (before %.4f mm)",
                  tty ? "\r\033[K" : "", obj->value("set", 0), obj->value("n", size_t{0}),
                  obj->value("rank", 0), obj->value("rms_mm", 0.0),
                  obj->value("rms_before_mm", 0.0));
      if (obj->contains("validation_rms_mm"))
        std::printf(", predicted this set before fitting it with RMS %.4f mm",
                    (*obj)["validation_rms_mm"].get<double>());
      std::printf("\n  calibrated model: %s\n  report: %s\n",
                  obj->value("calibrated_file", "").c_str(), obj->value("report_dir", "").c_str());
    } else if (cls == "ERROR" && !as_json) {
      std::fprintf(stderr, "robocald: %s\n", obj->value("message", "").c_str());
    }
    if (!as_json && tty && (have_bar || !progress.is_null())) {
      const int done = progress.value("points_done", 0), total = progress.value("points_total", 0);
      const int width = 30, filled = total > 0 ? width * done / total : 0;
      std::printf("\r\033[K[%s%s] %d/%d shell %d/%d left %s  bar %+.4f mm",
                  std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(), done,
                  total, progress.value("shell", 0), progress.value("shells", 0),
                  duration(progress.value("eta_s", 0.0)).c_str(), last_bar);
      std::fflush(stdout);
    }
    if (cls == "STATE" && until.count(obj->value("to", ""))) {
      exit_code = obj->value("to", "") == "done" ? 0 : 4;
      break;
    }
    std::fflush(stdout);
  }
  if (tty) std::printf("\n");
  return exit_code;
}

const RegisterCommand r1({"status", "robocald: state, run progress, devices", status});
const RegisterCommand r2({"watch", "robocald: live bar, progress and prompts", watch});
const RegisterCommand r3({"start", "robocald: start a calibration run", start});
const RegisterCommand r4({"confirm", "robocald: the bar is connected as asked", confirm});
const RegisterCommand r11({"nudge", "robocald: move the ball so the bar fits", nudge});
const RegisterCommand r5({"pause", "robocald: pause the run at the next step", pause});
const RegisterCommand r6({"resume", "robocald: resume a paused or interrupted run", resume});
const RegisterCommand r7({"abort", "robocald: stop the robot and end the run", abortRun});
const RegisterCommand r8({"result", "robocald: the latest fit", result});
const RegisterCommand r9({"runs", "robocald: the run history", runs});

}  // namespace
}  // namespace robocal::cli

namespace robocal::cli {
namespace {

// robocal cellsim SOCKET COMMAND...: one control command to a running robocal-cellsim.
int cellsim(const std::vector<std::string>& argv) {
  if (argv.size() < 2 || argv[0] == "--help") {
    std::printf(
        "usage: robocal cellsim SOCKET COMMAND...\n  Sends a control command to "
        "robocal-cellsim (status, connect B1C2 ..., fault ..., estop, quit).\n");
    return argv.empty() || argv[0] != "--help" ? 2 : 0;
  }
  std::string command;
  for (size_t i = 1; i < argv.size(); ++i) command += (i > 1 ? " " : "") + argv[i];
  std::printf("%s\n", cellsimControl(argv[0], command).c_str());
  return 0;
}

const RegisterCommand r10({"cellsim", "send a control command to robocal-cellsim", cellsim});

}  // namespace
}  // namespace robocal::cli
