// The run controller: its public API (called on the client loop; each call takes the shared
// state's lock once and never touches files or ports) and the run thread's main loop. A run's
// work is in ShellRunner (the shells), RunContext (moves, the bar, the operator), Centring and
// FitJob; what both threads see is in RunShared.
#include <robocal/daemon/run.hpp>

#include "fit_job.hpp"
#include "run_context.hpp"
#include "run_shared.hpp"
#include "shell_runner.hpp"

#include <robocal/drivers/errors.hpp>
#include <robocal/formats/error.hpp>
#include <robocal/planner/check.hpp>
#include <robocal/planner/plan_json.hpp>

#include <spdlog/spdlog.h>

#include <cmath>
#include <filesystem>
#include <thread>

namespace robocal::daemon {
namespace {
using json = nlohmann::json;
using proto::RunState;
}  // namespace

HealthOptions healthOptions(const DaemonConfig& config) {
  HealthOptions o;
  o.warn_ratio = config.check_warn_ratio;
  o.fail_ratio = config.check_fail_ratio;
  return o;
}

struct RunController::Impl {
  using Clock = std::chrono::steady_clock;
  DaemonConfig config;
  Model nominal;
  std::optional<CellConfig> cell;
  RunStore store;
  ModelStore models;
  RunShared shared;
  std::unique_ptr<CellIo> cell_io;
  RunContext ctx;
  FitJob fits;
  std::thread thread;

  Impl(DaemonConfig c, Model m, std::optional<CellConfig> cell_config, Publish publish,
       std::unique_ptr<CellIo> io)
      : config(std::move(c)),
        nominal(std::move(m)),
        cell(std::move(cell_config)),
        store(config.data_dir),
        models(config.data_dir),
        cell_io(io ? std::move(io) : makeDriverCell(config)),
        ctx(config, nominal, cell, publish, store, shared, *cell_io),
        fits(nominal, cell ? cell->work_volume : WorkVolume{}, healthOptions(config), models,
             shared, publish) {
    recoverFromDisk();
    ctx.connectDevices();  // the ports' state is in the log from the start
    thread = std::thread([this] { threadMain(); });
  }

  ~Impl() {
    shared.quit = true;
    shared.abort_requested = true;
    shared.wake();
    if (thread.joinable()) thread.join();
    fits.wait();
  }

  // Before the run thread starts: an unfinished run, the newest result, the bar's attachment and
  // the run history, as the last daemon left them.
  void recoverFromDisk() {
    shared.with([&](RunData& d) { recoverFromDisk(d); });
  }
  void recoverFromDisk(RunData& d) {
    if (auto id = store.latestUnfinished()) {
      RunDir dir = store.open(*id);
      json st = dir.state();
      if (st.value("status", "") == "running") {
        st["status"] = "interrupted";
        dir.setState(st);
        dir.logEvent({{"event", "interrupted"}, {"detail", "found unfinished at daemon start"}});
      }
      d.resumable_id = d.run_id = *id;
      d.state = RunState::kInterrupted;
      d.state_reason = "run " + *id + " was interrupted; resume continues it";
      recoverProgress(dir, d);
    }
    // `result` after a restart serves the newest fit on disk, not "no fit yet".
    std::vector<std::string> unreadable;
    if (auto r = store.latestResult(&unreadable)) {
      d.last_result = std::move(*r);
      spdlog::info("latest result: run {}, set {}", d.last_result.value("run", "?"),
                   d.last_result["set"].get<long>());
    }
    for (const std::string& why : unreadable) spdlog::warn("result file skipped: {}", why);
    if (auto c = store.latestCheck()) d.last_check = std::move(*c);
    std::string bar_problem;
    d.attachment = store.barAttachment(&bar_problem);
    if (!bar_problem.empty()) spdlog::warn("{}", bar_problem);
    if (d.attachment.maybe_attached)
      spdlog::info("the ball-bar may be attached (since run {}): the next run asks to detach it",
                   d.attachment.run.empty() ? "?" : d.attachment.run);
    for (const std::string& id : store.ids()) {
      const json st = store.open(id).state();
      d.runs.push_back({id, st.value("status", "?"), st.value("reason", "")});
    }
  }

  // An interrupted run's progress as its files say, for STATUS before the resume (it showed 0
  // of 0 points). Reading the samples cuts a row torn by the crash, with an event.
  void recoverProgress(RunDir& dir, RunData& d) {
    try {
      const Plan plan = parsePlan(readTextFile(dir.file("plan.json")), dir.file("plan.json"));
      const std::vector<Sample> samples = dir.loadSamples();
      d.shells_total = static_cast<int>(plan.shells.size());
      d.points_total = 0;
      for (const auto& shell : plan.shells)
        for (const auto& step : shell.steps) d.points_total += step.kind == StepKind::kPoint;
      d.points_done = static_cast<int>(samples.size());
      if (!samples.empty()) {
        d.shell_number = samples.back().shell;
        d.connection_name = connectionName({samples.back().ball_index, samples.back().chuck_index});
      }
    } catch (const std::exception& e) {
      spdlog::warn("run {}: its progress cannot be read: {}", dir.id(), e.what());
    }
  }

  // The run's state on disk, and in the history `runs` serves.
  void recordRunState(RunDir& dir, const json& state) {
    dir.setState(state);
    const RunSummary summary{dir.id(), state.value("status", "?"), state.value("reason", "")};
    shared.with([&](RunData& d) {
      for (RunSummary& r : d.runs)
        if (r.run == summary.run) {
          r = summary;
          return;
        }
      d.runs.push_back(summary);
    });
  }

  void threadMain() {
    auto next_connect = Clock::now();
    while (!shared.quit) {
      std::optional<RunJob> todo = shared.with([](RunData& d) {
        std::optional<RunJob> j = std::move(d.job);
        d.job.reset();
        d.starting = j && j->kind != RunJob::kClose;
        return j;
      });
      if (todo) {
        execute(std::move(*todo));
        shared.with([](RunData& d) { d.starting = false; });
        continue;
      }
      // Idle: keep the bar streaming to watchers and both ports ready, reconnecting now and then.
      const DeviceState devices = shared.with([](const RunData& d) { return d.devices; });
      if (Clock::now() >= next_connect && (!devices.bar_connected || !devices.val_connected)) {
        next_connect = Clock::now() + std::chrono::seconds(2);
        ctx.connectDevices();
      }
      if (!cell_io->poll(Clock::now() + std::chrono::milliseconds(20)))
        shared.waitFor(std::chrono::milliseconds(20));
    }
  }
  void execute(RunJob job) {
    if (job.kind == RunJob::kClose) return closeRun(job.run_id);
    shared.abort_requested = false;
    shared.pause_requested = false;
    ctx.forgetLinkFaults();  // what happened between runs is not this run's
    shared.with([](RunData& d) { d.stop_reason.clear(); });
    std::optional<RunDir> dir;
    try {
      Plan plan = job.plan;
      if (job.kind == RunJob::kStart) {
        // A port that went away since `start` was accepted: no run is made for nothing.
        try {
          ctx.ensureDevices();
        } catch (const StopRun& stop) {
          ctx.publish(proto::errorObject("run not started: " + stop.reason, "start"), false);
          ctx.setState(RunState::kError, "run not started: " + stop.reason);
          return;
        }
        dir = store.create(formatPlan(plan));
      } else {
        dir = store.open(job.run_id);
        plan = parsePlan(readTextFile(dir->file("plan.json")), dir->file("plan.json"));
      }
      shared.with([&](RunData& d) {
        d.run_id = dir->id();
        d.resumable_id.clear();
      });
      recordRunState(*dir, {{"status", "running"}});
      dir->logEvent({{"event", job.kind == RunJob::kStart ? "start" : "resume"}});
      ctx.setState(RunState::kChecking, "run " + dir->id() + ": checking the plan");
      if (!planPassesCheck(*dir, plan)) return;
      ctx.ensureDevices();
      ShellRunner(ctx, fits, *dir, plan).run();
      ctx.reportLinkFaults(*dir);
      // Done on disk only once the last fit is written: a kill during it leaves the run
      // interrupted, and its resume fits the set again (ShellRunner::run).
      ctx.setState(RunState::kSolving, "waiting for the last fit");
      fits.wait();
      recordRunState(*dir, {{"status", "done"}});
      dir->logEvent({{"event", "done"}});
      ctx.setState(RunState::kDone, "run " + dir->id() + " complete");
    } catch (const StopRun& stop) {
      stopped(dir, stop);
    } catch (const drivers::DriverError& e) {
      stopped(dir, {StopRun::kFault, e.what()});
    } catch (const FormatError& e) {
      // A run file that cannot be read (a garbled samples row, a damaged plan): a resume would
      // stop here again until the file is put right.
      stopped(dir, {StopRun::kFault, std::string("a run file cannot be read: ") + e.what()},
              "the robot is stopped; resume cannot go on until that file is repaired (fix or "
              "remove the line it names, docs/robocald.md), or abort the run");
    } catch (const std::exception& e) {
      stopped(dir, {StopRun::kFault, std::string("error: ") + e.what()});
    }
    shared.with([](RunData& d) { d.prompt.reset(); });
  }

  // The safety check of the plan the run follows; on violations the run ends before anything
  // moves, with the violations in the ERROR.
  bool planPassesCheck(RunDir& dir, const Plan& plan) {
    const auto violations = checkPlan(nominal, ctx.cellFor(plan), plan);
    if (violations.empty()) return true;
    json list = json::array();
    for (const auto& v : violations) list.push_back(describeViolation(v));
    dir.logEvent({{"event", "plan_rejected"}, {"violations", list}});
    recordRunState(dir, {{"status", "aborted"}, {"reason", "plan failed the safety check"}});
    ctx.publish(proto::toJson(proto::Error{std::to_string(violations.size()) +
                                               " safety violations in the plan; nothing moved",
                                           {},
                                           list.get<std::vector<std::string>>()}),
                false);
    ctx.setState(RunState::kError,
                 "plan failed the safety check: " + describeViolation(violations.front()));
    return false;
  }

  // `way_on`: what gets the run going again, for the operator (a pause says it).
  void stopped(std::optional<RunDir>& dir, const StopRun& stop,
               const std::string& way_on = "the robot is stopped, resume continues") {
    cell_io->halt();
    ctx.setBarOffset(0);
    const bool aborted = stop.kind == StopRun::kAbort;
    const std::string status = aborted ? "aborted" : "paused";
    if (dir) {
      try {
        ctx.reportLinkFaults(*dir);
        recordRunState(*dir, {{"status", status}, {"reason", stop.reason}});
        dir->logEvent({{"event", status}, {"reason", stop.reason}});
      } catch (const std::exception& e) {
        spdlog::error("cannot record the stop: {}", e.what());
      }
      if (!aborted) shared.with([&](RunData& d) { d.resumable_id = dir->id(); });
    }
    spdlog::warn("run {}: {}", status, stop.reason);
    ctx.setState(aborted ? RunState::kAborted : RunState::kPaused,
                 stop.reason + (aborted ? "" : "; " + way_on));
  }

  // Aborting a paused or interrupted run: nothing moves, the run is closed for good.
  void closeRun(const std::string& id) {
    const std::string reason = shared.with([](const RunData& d) { return d.stop_reason; });
    try {
      RunDir dir = store.open(id);
      recordRunState(dir, {{"status", "aborted"}, {"reason", reason}});
      dir.logEvent({{"event", "aborted"}, {"reason", reason}});
    } catch (const std::exception& e) {
      spdlog::error("cannot record that run {} is aborted: {}", id, e.what());
    }
    ctx.setState(RunState::kAborted, "run " + id + " closed: " + reason);
  }

  proto::Status statusObject() const {
    return shared.with([](const RunData& d) {
      proto::Status s;
      s.state = d.state;
      s.reason = d.state_reason;
      s.run = d.run_id;
      s.shell = d.shell_number;
      s.shells = d.shells_total;
      s.connection = d.connection_name;
      s.points_done = d.points_done;
      s.points_total = d.points_total;
      s.eta_s = d.eta_s;
      s.bar_attached = d.attachment.maybe_attached;
      s.devices.val = d.devices.val_connected;
      s.devices.bar = d.devices.bar_connected;
      if (!d.devices.val_error.empty()) s.devices.val_error = d.devices.val_error;
      if (!d.devices.bar_error.empty()) s.devices.bar_error = d.devices.bar_error;
      s.bar = d.latest_bar;
      s.prompt = d.prompt;
      s.resumable = d.resumable_id;
      return s;
    });
  }
};

namespace {
// "" when every configured device path exists; else which device's path is gone, and what to
// check. Ports found by USB serial number or description (no path) are left to the drivers.
std::string missingPort(const drivers::DriversConfig& drivers) {
  const std::pair<const char*, const drivers::SerialConfig*> ports[] = {
      {"the VAL II controller", &drivers.val.serial}, {"the ball-bar reader", &drivers.bar.serial}};
  for (const auto& [device, serial] : ports) {
    std::error_code ec;
    if (!serial->path.empty() && !std::filesystem::exists(serial->path, ec))
      return std::string(device) + "'s port " + serial->path +
             " is gone (unplugged, or another name now?): `robocal ports` lists what is there";
  }
  return {};
}

// Why the bar looks seated on the ball ("" when it reads as it did off the robot): a reading
// more than `threshold_mm` from the free bar's at the prompt, or a status line in its place.
std::string barSeatedProblem(const RunData& d, double threshold_mm) {
  if (!d.latest_bar || !d.free_bar_mm) return {};  // nothing to compare with
  char buf[240];
  if (d.latest_bar->kind != proto::BarKind::kReading) {
    std::snprintf(buf, sizeof buf,
                  "nudge refused: the ball-bar reports %s, as a seated bar pushed past its "
                  "range would: take the bar off the ball before nudging",
                  proto::barKindName(d.latest_bar->kind));
    return buf;
  }
  if (!d.latest_bar->deflection_mm) return {};
  const double change_mm = *d.latest_bar->deflection_mm - *d.free_bar_mm;
  if (std::abs(change_mm) <= threshold_mm) return {};
  std::snprintf(buf, sizeof buf,
                "nudge refused: the ball-bar reads %+.3f mm, %+.3f mm from its reading off the "
                "robot, so it looks seated: a nudge would move it at full speed. Confirm if the "
                "bar is seated; take it off the ball to nudge",
                *d.latest_bar->deflection_mm, change_mm);
  return buf;
}
}  // namespace

RunController::RunController(DaemonConfig config, Model nominal, std::optional<CellConfig> cell,
                             Publish publish, std::unique_ptr<CellIo> cell_io)
    : impl_(std::make_unique<Impl>(std::move(config), std::move(nominal), std::move(cell),
                                   std::move(publish), std::move(cell_io))) {}

RunController::~RunController() = default;

std::string RunController::start(const Plan& plan) {
  return impl_->shared.with([&](RunData& d) -> std::string {
    const char* state = proto::runStateName(d.state);
    if (d.busy()) return std::string("a run is in progress (") + state + ")";
    if (!d.resumable_id.empty() && d.state != RunState::kDone)
      return "run " + d.resumable_id + " is " + state +
             ": resume it or abort it before starting another";
    // Refused before a run folder exists: a missing port leaves no empty run in the history.
    // A device path that is gone now (an adapter unplugged, a pty closed) is refused at once:
    // the idle loop notices a lost port only at its next poll, after `start` was acknowledged.
    if (const std::string gone = missingPort(impl_->config.drivers); !gone.empty()) return gone;
    if (!d.devices.bar_connected)
      return "the ball-bar reader is not connected: " + d.devices.bar_error +
             " (robocald retries every 2 s; `robocal probe --bar PORT` checks the port)";
    if (!d.devices.val_connected)
      return "the VAL II controller is not connected: " + d.devices.val_error +
             " (robocald retries every 2 s; `robocal probe --val PORT` checks the port)";
    d.job = RunJob{RunJob::kStart, plan, {}};
    impl_->shared.wake();
    return {};
  });
}

std::string RunController::confirm(std::optional<int> shell) {
  return impl_->shared.with([&](RunData& d) -> std::string {
    if (!d.prompt) return "nothing to confirm: no prompt is pending";
    if (shell && *shell != d.prompt_shell)
      return "the pending prompt is for shell " + std::to_string(d.prompt_shell) + ", not " +
             std::to_string(*shell);
    ++d.confirms;
    return {};
  });
}

std::string RunController::nudge(std::optional<int> shell, double mm) {
  return impl_->shared.with([&](RunData& d) -> std::string {
    if (!d.prompt || d.prompt->action != proto::PromptAction::kConnect)
      return "nothing to nudge: no connect prompt is pending";
    if (shell && *shell != d.prompt_shell)
      return "the pending prompt is for shell " + std::to_string(d.prompt_shell);
    if (std::abs(mm) > 5.0) return "a nudge moves at most 5 mm";
    if (std::abs(d.nudged_mm + mm) > 10.0)
      return "nudges for this connection would pass 10 mm in all: check the set-up";
    if (d.nudge_mm) return "a nudge is still moving";
    // A nudge moves the ball at the controller's speed and is not stopped short: with the bar
    // seated it would stretch or crush it. A reading that has left the free bar's says seated.
    if (const std::string seated = barSeatedProblem(d, impl_->config.detached_change_mm);
        !seated.empty())
      return seated;
    d.nudge_mm = mm;
    d.nudged_mm += mm;
    return {};
  });
}

std::string RunController::pause(const std::string& reason) {
  return impl_->shared.with([&](RunData& d) -> std::string {
    if (d.state == proto::RunState::kPaused)
      return std::string("the run is already paused: resume continues it, abort ends it");
    if (!proto::isBusy(d.state))
      return std::string("no run is in progress (") + proto::runStateName(d.state) + ")";
    d.stop_reason = reason.empty() ? "paused by the operator" : "paused: " + reason;
    impl_->shared.pause_requested = true;
    return {};
  });
}

std::string RunController::resume(const std::string& run_id) {
  return impl_->shared.with([&](RunData& d) -> std::string {
    if (d.busy()) return std::string("a run is in progress (") + proto::runStateName(d.state) + ")";
    const std::string id = run_id.empty() ? d.resumable_id : run_id;
    if (id.empty()) return "no paused or interrupted run to resume";
    const auto it = std::find_if(d.runs.begin(), d.runs.end(),
                                 [&](const RunSummary& r) { return r.run == id; });
    if (it == d.runs.end()) return "no run " + id;
    if (it->status == "done" || it->status == "aborted") return "run " + id + " is " + it->status;
    d.job = RunJob{RunJob::kResume, {}, id};
    impl_->shared.wake();
    return {};
  });
}

RunController::Answer RunController::abort(const std::string& reason) {
  return impl_->shared.with([&](RunData& d) -> Answer {
    const bool running = d.busy();
    const std::string state = proto::runStateName(d.state);
    if (!running && d.resumable_id.empty())
      return {"nothing to abort: no run is in progress, paused or interrupted (" + state + ")", {}};
    d.stop_reason = reason.empty() ? "aborted by the operator" : "aborted: " + reason;
    if (running) {
      impl_->shared.abort_requested = true;
      return {{}, "stopping the robot; run " + d.run_id + " is aborted (" + state + ")"};
    }
    // A paused or interrupted run: the run thread closes it for good (files are its business).
    const std::string closed = d.resumable_id;
    d.resumable_id.clear();
    d.job = RunJob{RunJob::kClose, {}, closed};
    impl_->shared.wake();
    return {{}, "run " + closed + " (" + state + ") is closed; nothing was moving"};
  });
}

proto::Status RunController::status() const {
  return impl_->statusObject();
}

nlohmann::json RunController::result() const {
  return impl_->shared.with([](const RunData& d) -> json {
    if (d.last_result.is_null())
      return proto::toJson(
          proto::Result{false, "no fit yet", {}, 0, 0, {}, {}, {}, json::object()});
    return d.last_result;
  });
}

nlohmann::json RunController::checkResult() const {
  return impl_->shared.with([](const RunData& d) -> json {
    if (d.last_check.is_null())
      return proto::toJson(proto::Check{false, "no health check yet", {}, 0, {}, {}, {}, {}});
    return d.last_check;
  });
}

ModelStore& RunController::models() {
  return impl_->models;
}

nlohmann::json RunController::runs() const {
  return impl_->shared.with([](const RunData& d) {
    proto::Runs runs;
    for (const RunSummary& r : d.runs) runs.runs.push_back({r.run, r.status, r.reason});
    return proto::toJson(runs);
  });
}

}  // namespace robocal::daemon
