// robocald: the robot-cell daemon. One Boost.Asio event loop serves the clients (JSON lines over
// TCP); the run thread owns the serial drivers; planning and fits run on worker threads.
#include "compensate_request.hpp"

#include <robocal/build_info.hpp>
#include <robocal/calibration/plan_pipeline.hpp>
#include <robocal/daemon/client_hub.hpp>
#include <robocal/daemon/config.hpp>
#include <robocal/daemon/metrics.hpp>
#include <robocal/daemon/run.hpp>
#include <robocal/daemon/token.hpp>
#include <robocal/daemon/web_server.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/planner/cell_json.hpp>
#include <robocal/planner/check.hpp>
#include <robocal/planner/health_plan.hpp>
#include <robocal/planner/plan_json.hpp>
#include <robocal/proto/protocol.hpp>

#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>

#include <cstdio>
#include <future>

namespace asio = boost::asio;
using json = nlohmann::json;
using namespace robocal;
using namespace robocal::daemon;

namespace {

// robocald --help; the man page robocald(8) is made from it. %s: the default config, the
// default data_dir.
constexpr const char* kHelp = R"(usage: robocald [--config FILE] [--port N]
       robocald --version | --help

The robot-cell daemon of robocal. It owns the serial links to the VAL II controller and the
ball-bar reader, runs calibration runs from checked plans, streams live readings to any number
of clients (JSON lines over TCP) and fits the model when a shell set completes. systemd starts
it (robocald.service); `robocal status`, `watch`, `start` and the other daemon commands talk to it.

  -c, --config FILE     the configuration file    [%s]
  --port N              listen on port N instead of the file's port (0: any free port)
  --version             print the version and exit
  -h, --help            print this help and exit

Every key of the configuration file is checked at start; a wrong one stops the daemon with its
name (exit code 2). Runs are kept below data_dir [%s]; the token that commands
moving the robot need is made there at first start (file token: mode 0600, or 0640 for the
robocal group when the daemon runs in it, as under the unit). Once it listens it prints
"listening ADDRESS PORT".
)";

proto::Plan planSummary(const Plan& plan, const std::string& source) {
  const auto& s = plan.summary;
  return {source,
          s.shells,
          s.points,
          s.vias,
          s.dropped,
          s.duration_s,
          s.rank,
          s.condition_number,
          s.max_deviation_mm,
          s.predicted_deflection_mm,
          s.predicted_change_mm,
          s.predicted_work_volume_error_mm,
          s.predicted_whole_range_error_mm};
}
json planObject(const Plan& plan, const std::string& source) {
  return proto::toJson(planSummary(plan, source));
}

HubLimits hubLimits(const DaemonConfig& c) {
  HubLimits limits;
  limits.max_clients = c.max_clients;
  limits.max_line_bytes = c.max_line_bytes;
  limits.queue_max = c.client_queue_max;
  limits.stall_s = c.client_stall_s;
  limits.request_timeout_s = c.request_timeout_s;
  return limits;
}

WebLimits webLimits(const DaemonConfig& c) {
  WebLimits limits;
  limits.max_browsers = c.max_browsers;
  limits.max_message_bytes = c.max_line_bytes;
  limits.queue_max = c.client_queue_max;
  limits.stall_s = c.client_stall_s;
  limits.request_timeout_s = c.request_timeout_s;
  limits.allowed_origins = c.web_allowed_origins;
  return limits;
}

class Daemon {
 public:
  Daemon(asio::io_context& io, DaemonConfig config)
      : io_(io),
        config_(std::move(config)),
        nominal_(loadModelFile(config_.model)),
        cell_(config_.cell.empty() ? std::nullopt : std::optional(loadCellFile(config_.cell))),
        token_(loadOrCreateToken(config_.token_file)),
        hub_(
            io, hubLimits(config_),
            [this](ClientHub::ClientId id, const std::string& line) { onLine(id, line); },
            [] { return proto::versionObject(build::kVersion); }),
        run_(config_, nominal_, cell_, [this](json object, bool droppable) {
          // From the run and solver threads into the event loop.
          asio::post(io_, [this, object = std::move(object), droppable] {
            metrics_.observe(object);
            hub_.broadcast(object, droppable);
            if (web_ && web_->anyWatching()) web_->broadcast(proto::frame(object), droppable);
          });
        }) {
    if (config_.web_port >= 0) web_.emplace(io_, webLimits(config_), webHandlers());
  }

  // A plan being made when the daemon stops is awaited: its thread uses the daemon's members.
  ~Daemon() {
    if (plan_worker_.joinable()) plan_worker_.join();
  }
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  unsigned short listen() {
    return hub_.listen(config_.listen_address, static_cast<unsigned short>(config_.port));
  }
  // The console's port, when configured.
  std::optional<unsigned short> listenWeb() {
    if (!web_) return std::nullopt;
    return web_->listen(config_.web_address, static_cast<unsigned short>(config_.web_port));
  }

 private:
  WebServer::Handlers webHandlers() {
    WebServer::Handlers h;
    h.on_line = [this](WebServer::ClientId id, const std::string& line) { onLine(id, line); };
    h.greeting = [] { return proto::versionObject(build::kVersion); };
    h.metrics = [this] {
      Metrics::Clients clients;
      clients.tcp = static_cast<int>(hub_.clientCount());
      clients.web = web_->browserCount();
      clients.web_counts = web_->counts();
      return metrics_.text(status(), run_.result(), clients);
    };
    h.settings = [this] {
      return json{{"bar_soft_limit_mm", config_.bar_soft_limit_mm},
                  {"bar_hard_limit_mm", config_.bar_hard_limit_mm},
                  {"release", build::kVersion}};
    };
    return h;
  }

  // One id space for both transports: browsers' ids are WebServer's.
  void send(ClientHub::ClientId id, const json& object) {
    if (WebServer::owns(id)) {
      if (web_) web_->send(id, object);
    } else {
      hub_.send(id, object);
    }
  }
  void setWatching(ClientHub::ClientId id, bool watching) {
    if (WebServer::owns(id)) {
      if (web_) web_->setWatching(id, watching);
    } else {
      hub_.setWatching(id, watching);
    }
  }

  void onLine(ClientHub::ClientId id, const std::string& line) {
    proto::Request req;
    try {
      req = proto::parseRequest(line);
    } catch (const proto::RequestError& e) {
      send(id, proto::errorObject(e.what(), e.cmd()));
      return;
    }
    const std::string cmd = proto::cmdName(req.cmd);
    if (proto::needsToken(req.cmd) && !sameToken(req.token, token_)) {
      spdlog::warn("client {}: {} refused: {}", id, cmd,
                   req.token.empty() ? "no token" : "wrong token");
      send(id, proto::errorObject(req.token.empty() ? cmd + " needs the token (\"token\": ...)"
                                                    : "wrong token for " + cmd,
                                  cmd));
      return;
    }
    auto reply = [this, id, &req](const std::string& error, const std::string& ok_message = {}) {
      send(id, error.empty() ? proto::ackObject(req.cmd, ok_message)
                             : proto::errorObject(error, proto::cmdName(req.cmd)));
    };
    switch (req.cmd) {
      case proto::Cmd::kStatus:
        send(id, status());
        break;
      case proto::Cmd::kWatch:
        setWatching(id, req.watch_enable);
        send(id, proto::toJson(proto::Watch{req.watch_enable}));
        if (req.watch_enable) send(id, status());
        break;
      case proto::Cmd::kResult:
        send(id, run_.result());
        break;
      case proto::Cmd::kRuns:
        send(id, run_.runs());
        break;
      case proto::Cmd::kPlan:
        makePlan(id, req.plan_path, req.cell_path, req.check, false);
        break;
      case proto::Cmd::kStart:
        if (req.check) {
          std::string problem;  // a verdict needs a model to judge
          if (!run_.models().active(&problem))
            reply("the health check judges the active model: " + problem);
          else
            makePlan(id, {}, {}, true, true);
        } else if (!req.plan_path.empty() || !plan_)
          makePlan(id, req.plan_path, {}, false, true);
        else {
          send(id, planObject(*plan_, plan_source_));  // the plan the run will follow
          reply(run_.start(*plan_), "run starting with " + plan_source_);
        }
        break;
      case proto::Cmd::kConfirm:
        reply(run_.confirm(req.shell), "the run goes on");
        break;
      case proto::Cmd::kNudge:
        reply(run_.nudge(req.shell, req.nudge_mm), "moving the ball");
        break;
      case proto::Cmd::kPause:
        reply(run_.pause(req.reason), "stopping the robot; `resume` continues the run");
        break;
      case proto::Cmd::kResume:
        reply(run_.resume(req.run_id), "resuming");
        break;
      case proto::Cmd::kAbort: {
        const RunController::Answer a = run_.abort(req.reason);
        reply(a.error, a.message);
        break;
      }
      case proto::Cmd::kModels:
        send(id, proto::toJson(run_.models().list()));
        break;
      case proto::Cmd::kActivate:
        reply(run_.models().activate(req.model_version), "model version " +
                                                             std::to_string(req.model_version) +
                                                             " is active: compensate uses it");
        break;
      case proto::Cmd::kCompensate:
        send(id, compensateRequest(run_.models(), nominal_, req));
        break;
      case proto::Cmd::kCheckResult:
        send(id, run_.checkResult());
        break;
    }
  }

  // The run's STATUS with what the daemon itself knows: its clients and its plan.
  json status() const {
    proto::Status s = run_.status();
    s.clients = static_cast<int>(hub_.clientCount()) + (web_ ? web_->browserCount() : 0);
    s.client_counts = hub_.counts();
    if (plan_) s.plan = planSummary(*plan_, plan_source_);
    return proto::toJson(s);
  }

  // Loads or makes a plan on a worker thread (planning takes up to seconds), then replies on the
  // event loop and, for start, starts the run with it.
  void makePlan(ClientHub::ClientId id, const std::string& plan_path, const std::string& cell_path,
                bool check, bool then_start) {
    if (planning_) {
      send(id, proto::errorObject("a plan is being made; try again in a moment", "plan"));
      return;
    }
    planning_ = true;
    if (plan_worker_.joinable()) plan_worker_.join();  // the last one has posted its answer
    const std::string path =
        !plan_path.empty() ? plan_path : (cell_path.empty() && !check ? config_.plan : "");
    plan_worker_ = std::thread([this, id, path, cell_path, check, then_start] {
      std::optional<Plan> plan;
      std::string source, error;
      json violation_list = json::array();
      try {
        if (check) {
          if (!cell_) throw std::runtime_error("no cell configured to plan the health check with");
          plan = planCalibration(nominal_, *cell_, {PlanKind::kCheck, {}}).plan;
          source = "the health check of " + config_.cell;
        } else if (!path.empty()) {
          plan = loadPlanFile(path);
          source = path;
        } else {
          const CellConfig cell = !cell_path.empty() ? loadCellFile(cell_path)
                                  : cell_
                                      ? *cell_
                                      : throw std::runtime_error("no cell configured to plan with");
          plan = planCalibration(nominal_, cell, {PlanKind::kGrid, {}}).plan;
          source = !cell_path.empty() ? cell_path : config_.cell;
        }
        const auto violations = checkPlan(nominal_, cell_ ? *cell_ : plan->cell, *plan);
        for (const auto& v : violations) violation_list.push_back(describeViolation(v));
        if (!violations.empty())
          error = source + ": " + std::to_string(violations.size()) +
                  " safety violations, first: " + describeViolation(violations.front());
      } catch (const std::exception& e) {
        error = e.what();
      }
      asio::post(io_, [this, id, plan = std::move(plan), source, error, then_start,
                       violation_list = std::move(violation_list)]() mutable {
        planning_ = false;
        if (!error.empty()) {
          json e = proto::errorObject(error, then_start ? "start" : "plan");
          if (!violation_list.empty()) e["violations"] = violation_list;
          send(id, e);
          return;
        }
        plan_ = std::move(plan);
        plan_source_ = source;
        send(id, planObject(*plan_, plan_source_));
        if (then_start) {
          const std::string err = run_.start(*plan_);
          send(id, err.empty() ? proto::ackObject(proto::Cmd::kStart, "run starting with " + source)
                               : proto::errorObject(err, "start"));
        }
      });
    });
  }

  asio::io_context& io_;
  DaemonConfig config_;
  Model nominal_;
  std::optional<CellConfig> cell_;
  std::string token_;
  ClientHub hub_;
  Metrics metrics_;               // fed on the event loop, before hub_ and web_ see the object
  std::optional<WebServer> web_;  // the console and /metrics (web_port >= 0)
  RunController run_;
  std::optional<Plan> plan_;
  std::string plan_source_;
  bool planning_ = false;
  std::thread plan_worker_;  // makes or loads a plan off the event loop; joined, never detached
};

void setupLogging(const DaemonConfig& config) {
  std::vector<spdlog::sink_ptr> sinks{std::make_shared<spdlog::sinks::stderr_sink_mt>()};
  if (!config.log_file.empty())
    sinks.push_back(std::make_shared<spdlog::sinks::basic_file_sink_mt>(config.log_file));
  auto logger = std::make_shared<spdlog::logger>("robocald", sinks.begin(), sinks.end());
  logger->set_level(spdlog::level::from_str(config.log_level));
  logger->flush_on(spdlog::level::info);
  spdlog::set_default_logger(logger);
}

// The systemd watchdog is pinged from the event loop itself: a stalled loop stops the pings.
void watchdog(asio::steady_timer& timer, double interval_s) {
  sd_notify(0, "WATCHDOG=1");
  timer.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(interval_s)));
  timer.async_wait([&timer, interval_s](const boost::system::error_code& ec) {
    if (!ec) watchdog(timer, interval_s);
  });
}

}  // namespace

int main(int argc, char** argv) {
  std::string config_path = build::kDaemonConfigFile;
  int port_override = -1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if ((a == "--config" || a == "-c") && i + 1 < argc) {
      config_path = argv[++i];
    } else if (a == "--port" && i + 1 < argc) {
      port_override = std::atoi(argv[++i]);
    } else if (a == "--help" || a == "-h") {
      std::printf(kHelp, build::kDaemonConfigFile, DaemonConfig{}.data_dir.c_str());
      return 0;
    } else if (a == "--version") {
      std::printf("robocald %s\n", build::kVersion);
      return 0;
    } else {
      std::fprintf(stderr, "robocald: unknown argument '%s' (robocald --help)\n", a.c_str());
      return 2;
    }
  }
  DaemonConfig config;
  try {
    config = loadDaemonConfig(config_path);
    if (port_override >= 0) config.port = port_override;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "robocald: %s\n", e.what());
    return 2;
  }
  setupLogging(config);
  try {
    asio::io_context io;
    Daemon daemon(io, config);
    const unsigned short port = daemon.listen();
    spdlog::info("robocald {} listening on {}:{}", build::kVersion, config.listen_address, port);
    std::printf("listening %s %u\n", config.listen_address.c_str(), port);
    if (const auto web_port = daemon.listenWeb()) {
      spdlog::info("console and /metrics on http://{}:{}/", config.web_address, *web_port);
      std::printf("web %s %u\n", config.web_address.c_str(), *web_port);
    }
    std::fflush(stdout);

    asio::signal_set signals(io, SIGINT, SIGTERM);
    signals.async_wait([&](const boost::system::error_code&, int sig) {
      spdlog::info("signal {}: stopping", sig);
      sd_notify(0, "STOPPING=1");
      io.stop();
    });
    asio::steady_timer watchdog_timer(io);
    uint64_t usec = 0;
    double interval = config.watchdog_interval_s;
    if (interval <= 0 && sd_watchdog_enabled(0, &usec) > 0) interval = usec / 2e6;
    if (interval > 0) watchdog(watchdog_timer, interval);
    sd_notify(0, "READY=1");
    io.run();
  } catch (const std::exception& e) {
    spdlog::critical("robocald: {}", e.what());
    return 1;
  }
  return 0;
}
