// robocal as the operator's client of robocald: status, watch, start, confirm, pause, resume,
// abort, result, runs. Plain `nc localhost 7687` works too: the protocol is JSON lines.
#include "args.hpp"
#include "daemon_view.hpp"

#include <robocal/formats/error.hpp>
#include <robocal/kinematics/sample.hpp>
#include <robocal/proto/client.hpp>
#include <robocal/proto/objects.hpp>
#include <robocal/sim/operator.hpp>

#include <boost/asio/io_context.hpp>
#include <boost/asio/local/stream_protocol.hpp>
#include <boost/asio/read_until.hpp>
#include <boost/asio/streambuf.hpp>
#include <boost/asio/write.hpp>

#include <sys/ioctl.h>
#include <unistd.h>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <set>
#include <thread>

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

// Prints a reply, for a person (parsed by its class's struct) or (--json) as it came; returns
// the exit code (1 for ERROR).
int show(const json& reply, bool as_json) {
  const std::string cls = proto::objectClass(reply);
  if (as_json) {
    std::printf("%s\n", reply.dump().c_str());
  } else if (cls == proto::Error::kClass) {
    const auto e = proto::parseObject<proto::Error>(reply);
    std::fprintf(stderr, "robocald: %s\n", e.message.c_str());
    for (const std::string& v : e.violations.value_or(std::vector<std::string>{}))
      std::fprintf(stderr, "  %s\n", v.c_str());
  } else if (cls == proto::Ack::kClass) {
    const auto a = proto::parseObject<proto::Ack>(reply);
    const std::string message = a.message.value_or("");
    std::printf("ok: %s%s%s\n", proto::cmdName(a.cmd), message.empty() ? "" : ": ",
                message.c_str());
  } else if (cls == proto::Status::kClass) {
    std::fputs(statusText(proto::parseObject<proto::Status>(reply)).c_str(), stdout);
  } else if (cls == proto::Result::kClass) {
    std::fputs(resultText(proto::parseObject<proto::Result>(reply)).c_str(), stdout);
  } else if (cls == proto::Runs::kClass) {
    std::fputs(runsText(proto::parseObject<proto::Runs>(reply)).c_str(), stdout);
  } else if (cls == proto::Check::kClass) {
    const auto c = proto::parseObject<proto::Check>(reply);
    if (!c.available)
      std::printf("%s\n", c.message.c_str());
    else
      std::printf("run %s, model version %d, %s\n%s", c.run.c_str(), c.model_version,
                  c.date_utc.c_str(), c.text.c_str());
    // As robocal health: 0 pass, 4 warn, 5 fail (docs/health-check.md).
    if (c.available && c.status != "pass") return c.status == "warn" ? 4 : 5;
  } else if (cls == proto::Models::kClass) {
    std::fputs(modelsText(proto::parseObject<proto::Models>(reply)).c_str(), stdout);
  } else if (cls == proto::Plan::kClass) {
    std::fputs(planText(proto::parseObject<proto::Plan>(reply)).c_str(), stdout);
  } else {
    std::printf("%s\n", reply.dump(2).c_str());
  }
  return cls == proto::Error::kClass ? 1 : 0;
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
           const char* help, std::set<std::string> flags = {}) {
  flags.insert({"json", "help"});
  const Args args(argv, valued(extra), flags);
  if (args.flag("help")) {
    std::printf("%s%s", help, kCommon);
    return 0;
  }
  json req = {{"cmd", cmd}};
  if (with_token) req["token"] = token(args);
  if (fill) fill(args, req);
  auto client = connectTo(args);
  // `start` answers PLAN, then ACK or ERROR: every object up to the final one is shown.
  json reply = client->request(req, 30.0);
  while (proto::objectClass(reply) == proto::Plan::kClass && std::string(cmd) == "start") {
    show(reply, args.flag("json"));
    auto next = client->read(30.0);
    if (!next) throw proto::ClientError("robocald sent no ACK after the PLAN within 30 s");
    reply = *next;
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
int models(const std::vector<std::string>& argv) {
  return simple(argv, "models", false, {}, {},
                "usage: robocal models [options]\n\nThe calibrated models robocald keeps (one "
                "version per fit), the active one starred.\n");
}
int activate(const std::vector<std::string>& argv) {
  return simple(
      argv, "activate", true, {},
      [](const Args& a, json& r) {
        if (a.positional().size() != 1)
          throw UsageError("give the model's version (robocal models)");
        const std::string& v = a.positional()[0];
        char* end = nullptr;
        const long version = std::strtol(v.c_str(), &end, 10);
        if (v.empty() || *end || version < 1 || version > 1000000000)
          throw UsageError("the version must be a whole number (robocal models lists them)");
        r["version"] = version;
      },
      "usage: robocal activate VERSION [options]\n\nMakes a stored model the active one: "
      "robocald's compensate request uses it.\n");
}
int start(const std::vector<std::string>& argv) {
  return simple(
      argv, "start", true, {},
      [](const Args& a, json& r) {
        if (a.positional().size() > 1) throw UsageError("one plan file at most");
        if (a.flag("check") && !a.positional().empty())
          throw UsageError("--check runs the health check's own plan: no plan file with it");
        if (!a.positional().empty()) r["plan"] = a.positional()[0];
        if (a.flag("check")) r["check"] = true;
      },
      "usage: robocal start [PLAN.json | --check] [options]\n  Starts a calibration run (with the "
      "daemon's plan, or PLAN.json as robocald sees the path).\n  --check starts the five-minute "
      "health check of the active model instead (docs/health-check.md).\n",
      {"check"});
}
int checkResult(const std::vector<std::string>& argv) {
  return simple(argv, "check_result", false, {}, {},
                "usage: robocal check-result [options]\n  The latest health check's verdict: "
                "pass, warn or fail, and what moved.\n  exit status: 0 pass (or no check yet), 4 "
                "warn, 5 fail, 1 an error\n");
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
      "usage: robocal pause [--reason TEXT] [options]\n\n"
      "Stops the robot at once (mid-move if it is moving) and pauses the run; `robocal resume`\n"
      "continues it, re-planned from where the robot stands.\n");
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

// The terminal's width in columns (100 when it cannot be told).
std::size_t terminalWidth() {
  winsize ws{};
  if (::ioctl(STDOUT_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col >= 20) return ws.ws_col;
  return 100;
}

// A new connection to robocald, tried every 2 s until `timeout_s` after `started` (0: forever);
// null when the time is up.
std::unique_ptr<proto::Client> reconnect(const Args& args,
                                         std::chrono::steady_clock::time_point started,
                                         double timeout_s) {
  while (timeout_s <= 0 ||
         std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count() <
             timeout_s) {
    std::this_thread::sleep_for(std::chrono::seconds(2));
    try {
      return connectTo(args);
    } catch (const std::exception&) {  // not back yet
    }
  }
  return nullptr;
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
  // In a terminal one live line stays at the bottom: text goes above it, and it is redrawn.
  std::optional<proto::Progress> progress;
  std::optional<double> bar;
  bool live_shown = false;
  auto last_draw = started;
  const std::size_t width = terminalWidth();
  const auto say = [&](const std::string& text) {
    if (as_json) return;
    if (tty && live_shown) std::fputs("\r\033[K", stdout);
    live_shown = false;
    std::fputs((tty ? wrapText(text, width) : text).c_str(), stdout);
    std::fflush(stdout);
  };
  const auto drawLive = [&](bool force) {
    if (as_json || !tty || !progress) return;
    const auto now = std::chrono::steady_clock::now();
    if (!force && now - last_draw < std::chrono::milliseconds(100)) return;
    last_draw = now;
    std::printf("\r\033[K%s", progressLine(*progress, bar).c_str());
    std::fflush(stdout);
    live_shown = true;
  };
  std::optional<proto::Prompt> answered;  // the simulated operator answers each prompt once
  const auto onPrompt = [&](const proto::Prompt& prompt) {
    say(promptText(prompt) + "\n");
    if (operator_socket.empty() || prompt == answered) return;
    answered = prompt;
    // The live line names what the prompt is about, not the last shell's connection.
    if (progress && prompt.action == proto::PromptAction::kConnect && prompt.ball && prompt.chuck) {
      progress->shell = prompt.shell;
      progress->connection = connectionName({*prompt.ball - 1, *prompt.chuck - 1});
    }
    const auto control = [&](const std::string& c) { return cellsimControl(operator_socket, c); };
    for (const std::string& action : sim::answerPrompt(*client, prompt, control, tok, bar_mm))
      say("(simulated operator: " + action + ")\n");
  };
  int exit_code = 0;
  while (true) {
    if (timeout_s > 0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count() >
            timeout_s) {
      say("");
      std::fprintf(stderr, "robocal watch: timed out after %.0f s\n", timeout_s);
      return 3;
    }
    std::optional<json> obj;
    try {
      obj = client->read(0.5);
    } catch (const proto::ClientError& e) {
      // The daemon went away (a restart, an upgrade): say so on a line of its own, and watch
      // again once it is back.
      say(std::string("\n") + e.what() + "\nreconnecting every 2 s (Ctrl-C to stop)\n");
      client = reconnect(args, started, timeout_s);
      if (!client) {
        std::fprintf(stderr, "robocal watch: robocald did not come back within %.0f s\n",
                     timeout_s);
        return 3;
      }
      say("reconnected to robocald\n");
      client->send({{"cmd", "watch"}, {"enable", true}});
      continue;
    }
    if (!obj) continue;
    const std::string cls = proto::objectClass(*obj);
    if (as_json) std::printf("%s\n", obj->dump().c_str());
    if (cls == proto::Bar::kClass) {
      if (const auto b = proto::parseObject<proto::Bar>(*obj); b.deflection_mm)
        bar = b.deflection_mm;
      drawLive(false);
      continue;
    }
    std::optional<proto::RunState> reached;  // a STATE's `to`
    if (cls == proto::Status::kClass) {  // on attach: where the run is, and any prompt that waits
      const auto s = proto::parseObject<proto::Status>(*obj);
      progress = s.progress();
      say(stateText(s.state, s.reason));
      if (s.prompt) onPrompt(*s.prompt);
    } else if (cls == proto::Progress::kClass) {
      progress = proto::parseObject<proto::Progress>(*obj);
    } else if (cls == proto::State::kClass) {
      const auto st = proto::parseObject<proto::State>(*obj);
      say(stateText(st));
      reached = st.to;
    } else if (cls == proto::Prompt::kClass) {
      onPrompt(proto::parseObject<proto::Prompt>(*obj));
    } else if (cls == proto::Result::kClass) {
      say("\nRESULT\n" + resultText(proto::parseObject<proto::Result>(*obj)));
    } else if (cls == proto::Error::kClass) {
      say("");
      std::fprintf(stderr, "robocald: %s\n",
                   proto::parseObject<proto::Error>(*obj).message.c_str());
    } else if (cls == proto::Event::kClass) {
      const auto e = proto::parseObject<proto::Event>(*obj);
      if (e.event == "connection_check" && !e.details.value("ok", true))
        say("connection check failed on shell " + std::to_string(e.details.value("shell", 0)) +
            "\n");
      if (e.event == "adaptive_dwell_off")
        say("shell " + std::to_string(e.details.value("shell", 0)) + ": " +
            e.details.value("reason", std::string()) + "\n");
    }
    drawLive(true);
    if (reached && until.count(proto::runStateName(*reached))) {
      exit_code = *reached == proto::RunState::kDone ? 0 : 4;
      break;
    }
    std::fflush(stdout);
  }
  if (tty && live_shown) std::printf("\n");
  return exit_code;
}

const RegisterCommand r1({"status", "robocald: state, run progress, devices", status});
const RegisterCommand r2({"watch", "robocald: live bar, progress and prompts", watch});
const RegisterCommand r3({"start", "robocald: start a calibration run", start});
const RegisterCommand r4({"confirm", "robocald: the bar is connected as asked", confirm});
const RegisterCommand r11({"nudge", "robocald: move the ball so the bar fits", nudge});
const RegisterCommand r5({"pause", "robocald: stop the robot now; resume continues", pause});
const RegisterCommand r6({"resume", "robocald: resume a paused or interrupted run", resume});
const RegisterCommand r7({"abort", "robocald: stop the robot and end the run", abortRun});
const RegisterCommand r8({"result", "robocald: the latest fit", result});
const RegisterCommand r9({"runs", "robocald: the run history", runs});
const RegisterCommand r14({"check-result", "robocald: the latest health check's verdict",
                           checkResult});
const RegisterCommand r12({"models", "robocald: the stored calibrated models", models});
const RegisterCommand r13({"activate", "robocald: make a stored model the active one", activate});

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
