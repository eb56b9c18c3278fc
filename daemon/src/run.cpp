#include <robocal/daemon/run.hpp>

#include <robocal/daemon/connection_check.hpp>
#include <robocal/daemon/shell_watch.hpp>
#include <robocal/daemon/time_left.hpp>

#include <robocal/drivers/bar.hpp>
#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/val.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/formats/report.hpp>
#include <robocal/formats/samples_csv.hpp>
#include <robocal/kinematics/kinematics.hpp>
#include <robocal/planner/check.hpp>
#include <robocal/planner/plan_json.hpp>
#include <robocal/proto/protocol.hpp>
#include <robocal/solver/calibrate.hpp>

#include <spdlog/spdlog.h>
#include <boost/asio/io_context.hpp>

#include <Eigen/LU>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <future>
#include <limits>
#include <map>
#include <numbers>
#include <set>

namespace robocal::daemon {
namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;
namespace asio = boost::asio;

constexpr double kRadPerDeg = std::numbers::pi / 180.0;

// Why the run left the normal path. Pause and fault leave it resumable; abort does not.
struct StopRun {
  enum Kind { kPause, kFault, kAbort } kind;
  std::string reason;
};
// The bar passed the soft limit during a move: stop, correct, re-plan.
struct Recentre {
  double deflection_mm;
};

drivers::Joints6 toDriver(const JointsDeg& q) {
  drivers::Joints6 out{};
  for (int j = 0; j < kJointCount; ++j) out[j] = q[j];
  return out;
}
JointsDeg fromDriver(const drivers::Joints6& q) {
  JointsDeg out;
  for (int j = 0; j < kJointCount; ++j) out[j] = q[j];
  return out;
}

std::int64_t monotonicMicros(Clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::microseconds>(t.time_since_epoch()).count();
}

Clock::duration fromSeconds(double seconds) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

// One data point's timing, from the end of its move: the dwell (settle) until the bar window
// opens, and the way to the sample's fsync. Logged as a "timing" event in the run's event log
// (`robocal run-timing` summarises them; docs/reliability.md, dwell timing).
struct PointTiming {
  Clock::time_point motion_complete, bar_window_start, where_end, sample_on_disk;

  static double toMicrosecond(double ms) { return std::round(ms * 1e3) / 1e3; }
  static double msBetween(Clock::time_point from, Clock::time_point to) {
    return toMicrosecond(std::chrono::duration<double, std::milli>(to - from).count());
  }
  nlohmann::json toEvent(int shell, double lat_deg, double lon_deg, double settle_s) const {
    const double settle_achieved_ms = msBetween(motion_complete, bar_window_start);
    return {{"event", "timing"},
            {"shell", shell},
            {"lat_deg", lat_deg},
            {"lon_deg", lon_deg},
            {"settle_s", settle_s},
            {"settle_achieved_ms", settle_achieved_ms},
            {"settle_error_ms", toMicrosecond(settle_achieved_ms - settle_s * 1e3)},
            {"where_ms", msBetween(bar_window_start, where_end)},
            {"motion_to_disk_ms", msBetween(motion_complete, sample_on_disk)}};
  }
};

proto::BarKind wireKind(drivers::BarLineKind kind) {
  switch (kind) {
    case drivers::BarLineKind::kReading:
      return proto::BarKind::kReading;
    case drivers::BarLineKind::kOverRange:
      return proto::BarKind::kOverRange;
    case drivers::BarLineKind::kNoProbe:
      return proto::BarKind::kNoProbe;
    case drivers::BarLineKind::kDeviceError:
    case drivers::BarLineKind::kGarbage:
      break;
  }
  return proto::BarKind::kDeviceError;
}

// A data point of a shell, as the samples file identifies it.
std::pair<double, double> pointKey(double lat_deg, double lon_deg) {
  return {std::round(lat_deg * 1e3) / 1e3, std::round(lon_deg * 1e3) / 1e3};
}

}  // namespace

struct RunController::Impl {
  DaemonConfig config;
  Model nominal;
  std::optional<CellConfig> cell;
  Publish publish;
  RunStore store;

  // --- shared with the client loop (under mutex) ---
  mutable std::mutex mutex;
  std::condition_variable wake;
  struct Job {
    enum Kind { kStart, kResume } kind;
    Plan plan;
    std::string run_id;
  };
  std::optional<Job> job;
  std::string state = "idle";
  std::string state_reason;
  std::string run_id;        // current or last run
  std::string resumable_id;  // a paused or interrupted run
  json prompt;               // the pending PROMPT, null when none
  int prompt_shell = 0;
  int confirms = 0;
  std::optional<double> nudge_mm;  // requested, not yet done
  double nudged_mm = 0;            // done for the pending prompt
  int shell_number = 0, shells_total = 0, points_done = 0, points_total = 0;
  double eta_s = 0;
  std::string connection_name;  // the shell's connection, e.g. "B1C3"
  json latest_bar;
  json last_result;
  bool val_connected = false, bar_connected = false;
  std::string val_error, bar_error;  // why a device is not connected ("" when it is)
  BarAttachment attachment;          // persisted in <data_dir>/bar.json
  std::atomic<bool> abort_requested{false}, pause_requested{false}, quit{false};
  std::string stop_reason;

  // --- run thread only ---
  asio::io_context io;
  std::unique_ptr<drivers::ValController> val;
  std::unique_ptr<drivers::BarReader> bar;
  std::optional<drivers::BarReading> last_reading;
  std::vector<double> window;  // readings collected while averaging
  bool collecting = false;
  double bar_offset_mm = 0;  // nominal + extension of the attached bar (0: none attached)
  std::future<void> solver;
  std::thread thread;

  Impl(DaemonConfig c, Model m, std::optional<CellConfig> cell_config, Publish p)
      : config(std::move(c)),
        nominal(std::move(m)),
        cell(std::move(cell_config)),
        publish(std::move(p)),
        store(config.data_dir) {
    if (auto id = store.latestUnfinished()) {
      RunDir dir = store.open(*id);
      json st = dir.state();
      if (st.value("status", "") == "running") {
        st["status"] = "interrupted";
        dir.setState(st);
        dir.logEvent({{"event", "interrupted"}, {"detail", "found unfinished at daemon start"}});
      }
      resumable_id = *id;
      run_id = *id;
      state = "interrupted";
      state_reason = "run " + *id + " was interrupted; resume continues it";
    }
    // `result` after a restart serves the newest fit on disk, not "no fit yet".
    std::vector<std::string> unreadable;
    if (auto r = store.latestResult(&unreadable)) {
      last_result = std::move(*r);
      spdlog::info("latest result: run {}, set {}", last_result.value("run", "?"),
                   last_result["set"].get<long>());
    }
    for (const std::string& why : unreadable) spdlog::warn("result file skipped: {}", why);
    std::string bar_problem;
    attachment = store.barAttachment(&bar_problem);
    if (!bar_problem.empty()) spdlog::warn("{}", bar_problem);
    if (attachment.maybe_attached)
      spdlog::info("the ball-bar may be attached (since run {}): the next run asks to detach it",
                   attachment.run.empty() ? "?" : attachment.run);
    connectDevices();  // the ports' state is in the log from the start
    thread = std::thread([this] { threadMain(); });
  }

  ~Impl() {
    quit = true;
    abort_requested = true;
    wake.notify_all();
    if (thread.joinable()) thread.join();
    if (solver.valid()) solver.wait();
  }

  // ------------------------------------------------------------------ state and events
  void setState(const std::string& s, const std::string& reason = {}) {
    std::string from;
    {
      std::lock_guard lock(mutex);
      from = state;
      state = s;
      state_reason = reason;
    }
    json ev = {{"class", "STATE"}, {"from", from}, {"to", s}};
    if (!reason.empty()) ev["reason"] = reason;
    spdlog::info("state {} -> {}{}{}", from, s, reason.empty() ? "" : ": ", reason);
    publish(ev, false);
  }

  void event(RunDir& dir, json ev) {
    dir.logEvent(ev);
    ev["class"] = "EVENT";
    publish(ev, false);
  }

  void checkpoint() {
    if (abort_requested) throw StopRun{StopRun::kAbort, stopReason("abort requested")};
    if (pause_requested) throw StopRun{StopRun::kPause, stopReason("pause requested")};
  }
  std::string stopReason(const std::string& fallback) {
    std::lock_guard lock(mutex);
    return stop_reason.empty() ? fallback : stop_reason;
  }

  // ------------------------------------------------------------------ devices
  void onBarLine(const drivers::BarReading& r) {
    last_reading = r;
    if (collecting && r.kind == drivers::BarLineKind::kReading) window.push_back(r.value_mm);
    json b = {{"class", "BAR"},
              {"seq", r.sequence},
              {"kind", proto::barKindName(wireKind(r.kind))},
              {"t_us", monotonicMicros(r.time)}};
    if (r.kind == drivers::BarLineKind::kReading) {
      b["deflection_mm"] = r.value_mm;
      if (bar_offset_mm > 0) b["length_mm"] = bar_offset_mm + r.value_mm;
    }
    {
      std::lock_guard lock(mutex);
      latest_bar = b;
    }
    publish(b, true);
  }

  // Connects each device that is not connected and records the outcome for STATUS and `start`;
  // the log says each change of a port's state (connected, or why not). Never throws.
  void connectDevices() {
    const auto attempt = [](const char* name, const drivers::SerialConfig& port, bool was_connected,
                            const std::string& old_error, const std::function<void()>& connect) {
      std::string error;
      try {
        connect();
      } catch (const std::exception& e) {
        error = e.what();
        if (error.empty()) error = "cannot connect";
      }
      const std::string where = !port.path.empty() ? port.path
                                : !port.usb_serial.empty()
                                    ? "USB serial " + port.usb_serial
                                    : "USB description \"" + port.usb_description + "\"";
      if (error.empty() && !was_connected)
        spdlog::info("{} connected ({})", name, where);
      else if (!error.empty() && (was_connected || error != old_error))
        spdlog::warn("{} not connected ({}): {}", name, where, error);
      return error;
    };
    std::string bar_err = attempt(
        "ball-bar reader", config.drivers.bar.serial, bar && bar->isConnected(), bar_error, [&] {
          if (!bar) {
            bar = std::make_unique<drivers::BarReader>(io, config.drivers.bar);
            bar->onLine([this](const drivers::BarReading& r) { onBarLine(r); });
          }
          if (!bar->isConnected()) bar->connect();
        });
    std::string val_err = attempt(
        "VAL II controller", config.drivers.val.serial, val && val->isConnected(), val_error, [&] {
          if (!val) val = std::make_unique<drivers::ValController>(io, config.drivers.val);
          if (!val->isConnected()) val->connect();
        });
    std::lock_guard lock(mutex);
    bar_error = std::move(bar_err);
    val_error = std::move(val_err);
    bar_connected = bar && bar->isConnected();
    val_connected = val && val->isConnected();
  }

  // Before a run: both devices answer, or the run stops with the port's error.
  void ensureDevices() {
    connectDevices();
    std::lock_guard lock(mutex);
    if (!bar_connected) throw StopRun{StopRun::kFault, "ball-bar reader: " + bar_error};
    if (!val_connected) throw StopRun{StopRun::kFault, "VAL II controller: " + val_error};
  }

  // The bar may be attached from now on (or no longer), on disk before anything moves.
  void setAttachment(const BarAttachment& a) {
    store.setBarAttachment(a);
    std::lock_guard lock(mutex);
    attachment = a;
  }
  bool barMaybeAttached() const {
    std::lock_guard lock(mutex);
    return attachment.maybe_attached;
  }

  // Runs the driver loop for a while (bar lines arrive), checking stop requests.
  void spin(double seconds, bool watch_bar) {
    spinUntil(Clock::now() + fromSeconds(seconds), watch_bar);
  }
  // The same until a deadline, which it does not overshoot by more than the event loop's wake-up
  // (each slice ends at the deadline, not 10 ms after the last check).
  void spinUntil(Clock::time_point until, bool watch_bar) {
    for (auto now = Clock::now(); now < until; now = Clock::now()) {
      checkpoint();
      io.restart();
      io.run_until(std::min(until, now + std::chrono::milliseconds(10)));
      if (watch_bar) watchBar(false);
    }
  }

  // Throws StopRun (fault) when the bar is out of range, silent, or past the hard limit; and
  // Recentre past the soft limit when asked.
  void watchBar(bool recentre) {
    if (!bar || !bar->isConnected()) throw StopRun{StopRun::kFault, "ball-bar reader disconnected"};
    if (bar->isStale())
      throw StopRun{StopRun::kFault, "no ball-bar reading for " +
                                         std::to_string(config.drivers.bar.stale_after_s) + " s"};
    if (!last_reading) return;
    if (last_reading->kind != drivers::BarLineKind::kReading)
      throw StopRun{StopRun::kFault, std::string("ball-bar reports ") +
                                         drivers::barLineKindName(last_reading->kind)};
    const double d = last_reading->value_mm;
    if (std::abs(d) > config.bar_hard_limit_mm)
      throw StopRun{StopRun::kFault, "bar deflection " + std::to_string(d) +
                                         " mm past the hard limit " +
                                         std::to_string(config.bar_hard_limit_mm) + " mm"};
    if (recentre && std::abs(d) > config.bar_soft_limit_mm) throw Recentre{d};
  }

  // A joint move, watched: stop requests, controller errors, and the bar. With the bar attached
  // its limits; believed detached, a reading that changes (the bar is still attached after all).
  JointsDeg move(const JointsDeg& target, bool bar_attached, bool recentre) {
    checkpoint();
    if (bar_attached) watchBar(recentre);  // nothing starts with the bar already in fault
    std::optional<double> detached_reading;
    if (!bar_attached && last_reading && last_reading->kind == drivers::BarLineKind::kReading)
      detached_reading = last_reading->value_mm;
    const drivers::WhereReply w =
        val->moveJoints(toDriver(target), [&](const drivers::WhereReply&) {
          checkpoint();
          if (bar_attached)
            watchBar(recentre);
          else
            watchDetached(detached_reading);
        });
    return fromDriver(w.joints_deg);
  }

  // The bar is believed detached: a reading in range that moves with the robot (or runs out of
  // range) says otherwise.
  void watchDetached(const std::optional<double>& reading_at_start) {
    if (!reading_at_start || !last_reading) return;
    const bool over_range = last_reading->kind == drivers::BarLineKind::kOverRange;
    if (last_reading->kind != drivers::BarLineKind::kReading && !over_range) return;
    const double change_mm = over_range ? std::numeric_limits<double>::infinity()
                                        : last_reading->value_mm - *reading_at_start;
    if (std::abs(change_mm) <= config.detached_change_mm) return;
    BarAttachment doubt = attachmentNow();
    doubt.maybe_attached = true;
    setAttachment(doubt);  // the next start or resume asks to detach it first
    char buf[64];
    std::snprintf(buf, sizeof buf, over_range ? "from %+.3f mm to over range" : "by %+.3f mm",
                  over_range ? *reading_at_start : change_mm);
    throw StopRun{StopRun::kFault, std::string("the ball-bar reading changed ") + buf +
                                       " while the robot moved with the bar believed detached: "
                                       "check that the bar is off the robot"};
  }
  BarAttachment attachmentNow() const {
    std::lock_guard lock(mutex);
    return attachment;
  }

  // Faults the drivers absorb (a garbled or cut-off bar line, a WHERE asked again) leave no pause
  // behind: the growth of the drivers' fault counters goes to the event log as "link_faults".
  std::map<std::string, long> linkFaultCounts() const {
    std::map<std::string, long> c;
    if (bar) {
      const drivers::BarStats& b = bar->stats();
      c["bar_garbage_lines"] = b.garbage_lines;
      c["bar_partial_lines"] = b.partial_lines;
      c["bar_timeouts"] = b.timeouts;
      c["bar_disconnects"] = b.disconnects;
      c["bar_device_errors"] = b.device_errors;
    }
    if (val) {
      const drivers::ValStats& v = val->stats();
      c["val_timeouts"] = v.timeouts;
      c["val_controller_errors"] = v.controller_errors;
      c["val_where_retries"] = v.where_retries;
      c["val_unsolicited_lines"] = v.unsolicited_lines;
    }
    return c;
  }
  std::map<std::string, long> link_faults_reported;  // run thread only
  void reportLinkFaults(RunDir& dir) {
    const std::map<std::string, long> now = linkFaultCounts();
    json ev = {{"event", "link_faults"}};
    for (const auto& [name, count] : now)
      if (count > link_faults_reported[name]) ev[name] = count - link_faults_reported[name];
    link_faults_reported = now;
    if (ev.size() > 1) event(dir, ev);
  }

  void stopRobot() {
    if (!val || !val->isConnected()) return;
    try {
      val->abort();
    } catch (const std::exception& e) {
      spdlog::error("ABORT failed: {}", e.what());
    }
  }

  // ------------------------------------------------------------------ the operator
  // Waits for the operator's confirm; `on_nudge` (when given) carries out nudge requests.
  void waitConfirm(RunDir& dir, json prompt_object, int shell,
                   const std::function<void(double)>& on_nudge = {}) {
    int seen;
    {
      std::lock_guard lock(mutex);
      prompt = prompt_object;
      prompt_shell = shell;
      seen = confirms;
      nudge_mm.reset();
      nudged_mm = 0;
    }
    setState("awaiting_confirm", prompt_object.value("message", ""));
    dir.logEvent({{"event", "prompt"}, {"prompt", prompt_object}});
    publish(prompt_object, false);
    while (true) {
      checkpoint();
      {
        std::lock_guard lock(mutex);
        if (confirms != seen) {
          prompt = nullptr;
          break;
        }
      }
      std::optional<double> nudge;
      {
        std::lock_guard lock(mutex);
        nudge.swap(nudge_mm);
      }
      if (nudge && on_nudge) {
        on_nudge(*nudge);
        dir.logEvent({{"event", "nudged"}, {"shell", shell}, {"mm", *nudge}});
        publish({{"class", "EVENT"}, {"event", "nudged"}, {"shell", shell}, {"mm", *nudge}}, false);
      }
      io.restart();
      io.run_for(std::chrono::milliseconds(20));
    }
    dir.logEvent({{"event", "confirmed"}, {"shell", shell}});
  }

  // ------------------------------------------------------------------ the run
  const CellConfig& cellFor(const Plan& plan) const { return cell ? *cell : plan.cell; }

  Model refine(const std::vector<Sample>& samples, const Plan& plan) {
    const ModelUncertainty& u = cellFor(plan).uncertainty;
    ParamVector sigma;
    for (int i = 0; i < kParamCount; ++i) {
      const bool joint = (i % (kLinkParamCount + kJointParamCount)) >= kLinkParamCount;
      switch (paramKind(i)) {
        case ParamKind::kTranslation:
          sigma[i] = u.translation_sigma_mm;
          break;
        case ParamKind::kAngle:
          sigma[i] = (joint ? u.joint_offset_sigma_deg : u.link_angle_sigma_deg) * kRadPerDeg;
          break;
        case ParamKind::kGain:
          sigma[i] = u.gain_sigma;
          break;
      }
    }
    SolveOptions opt;
    opt.prior_sigma = 3.0 * sigma;  // generous: the prior only steadies what data cannot see
    opt.max_iterations = 20;
    return withParams(nominal, solveCalibration(nominal, samples, opt).params);
  }

  void recordReplan(RunDir& dir, int& replans, const ShellPlan& shell, std::size_t next,
                    const std::string& why) {
    ++replans;
    json steps = json::array();
    for (std::size_t i = next; i < shell.steps.size(); ++i) {
      const auto& s = shell.steps[i];
      steps.push_back(
          {{"kind", s.kind == StepKind::kPoint ? "point" : "via"},
           {"joints", std::vector<double>(s.joints_deg.data(), s.joints_deg.data() + 6)},
           {"lat_deg", s.lat_deg},
           {"lon_deg", s.lon_deg}});
    }
    std::filesystem::create_directories(dir.file("replans"));
    dir.writeJson("replans/" + std::to_string(replans) + ".json",
                  {{"shell", shell.shell}, {"from_step", next}, {"why", why}, {"steps", steps}});
    dir.logEvent({{"event", "replan"},
                  {"shell", shell.shell},
                  {"from_step", next},
                  {"why", why},
                  {"file", "replans/" + std::to_string(replans) + ".json"}});
  }

  // The corrective move toward zero deflection: the ball moved along the bar by -deflection.
  // Checked like a planned pose before anything moves (limits, singularities, bar-tool angle,
  // clearances; not the deviation from the shell, which is what it corrects), and a move of a few
  // mm must stay a small turn of every joint: a larger one means a singular pose or a wrong model.
  // Either stops the run.
  JointsDeg correction(const Model& model, const CellConfig& cell_config, const ShellPlan& shell,
                       const JointsDeg& q, double deflection_mm) {
    const Connection& c = shell.connection;
    const Kinematics kin(model);
    const Eigen::Vector3d ball = kin.ballPosition(q, model.balls_mm[c.ball_index]);
    const Eigen::Vector3d u = (ball - model.chucks_mm[c.chuck_index]).normalized();
    const Eigen::Matrix<double, 3, 6> jac =
        kin.jointJacobian(q, model.balls_mm[c.ball_index]).topRows<3>();
    const Eigen::Vector3d move = -deflection_mm * u;
    const Eigen::Matrix<double, 6, 1> dq =
        jac.transpose() * (jac * jac.transpose()).partialPivLu().solve(move);
    const JointsDeg target = q + dq / kRadPerDeg;
    constexpr double kMaxTurnDegPerMm = 2.0;
    const double max_turn_deg = (dq / kRadPerDeg).cwiseAbs().maxCoeff();
    std::string problem;
    if (!target.allFinite() ||
        max_turn_deg > kMaxTurnDegPerMm * std::max(1.0, std::abs(deflection_mm)))
      problem = "it would turn a joint by " + std::to_string(max_turn_deg) + " deg";
    else
      problem =
          ShellPlanner(model, cell_config)
              .poseProblem(c, shell.radius_mm, target, std::numeric_limits<double>::infinity());
    if (!problem.empty())
      throw StopRun{StopRun::kFault, "corrective move of " + std::to_string(deflection_mm) +
                                         " mm on shell " + std::to_string(shell.shell) +
                                         " refused: " + problem};
    return target;
  }

  void updateProgress(int done, int total, double time_left_s) {
    json p;
    {
      std::lock_guard lock(mutex);
      points_done = done;
      points_total = total;
      eta_s = time_left_s;
      p = {{"class", "PROGRESS"},    {"shell", shell_number},
           {"shells", shells_total}, {"connection", connection_name},
           {"points_done", done},    {"points_total", total},
           {"eta_s", eta_s}};
    }
    publish(p, false);
  }

  // The robot time a data point of this shell takes by the plan's duration model, with this
  // daemon's dwell and bar window in place of the cell's planned dwell.
  double plannedPointSeconds(const ShellPlan& shell, const CellConfig& cell_config) const {
    const ShellSummary& s = shell.summary;
    if (s.points <= 0) return 0;
    const double moves_s = std::max(0.0, s.duration_s - s.points * cell_config.motion.settle_s);
    return moves_s / s.points + config.settle_s + config.bar_window_s;
  }

  // After a connect: the ball moves a small step along the expected bar line and back past the
  // start, and the bar must follow (connection_check.hpp). The ball ends where it started.
  void verifyConnection(RunDir& dir, const Model& model, const CellConfig& cell_config,
                        const ShellPlan& shell, JointsDeg& q) {
    const double step_mm = std::min(config.connection_check_mm, 0.4 * config.bar_soft_limit_mm);
    if (step_mm <= 0) return;
    // Averaged over at least half a second: the steps are tenths of a millimetre, the noise of
    // one reading a few hundredths.
    const auto settledMeasurement = [&] {
      spin(config.settle_s, true);
      return measureHere(std::max(config.bar_window_s, 0.5));
    };
    const JointsDeg start = q;
    double before_mm = settledMeasurement().deflection_mm;
    // Toward zero first: the bar stays inside its soft limit all the way.
    const double sign = before_mm > 0 ? -1.0 : 1.0;
    std::vector<ProbeStep> steps;
    json record = json::array();
    for (const double commanded_mm : {sign * step_mm, -2.0 * sign * step_mm}) {
      q = move(correction(model, cell_config, shell, q, -commanded_mm), true, false);
      const double after_mm = settledMeasurement().deflection_mm;
      steps.push_back({commanded_mm, after_mm - before_mm});
      record.push_back(
          {{"commanded_mm", commanded_mm}, {"reading_change_mm", after_mm - before_mm}});
      before_mm = after_mm;
    }
    q = move(start, true, false);
    const std::string problem = connectionCheckProblem(steps);
    event(dir, {{"event", "connection_check"},
                {"shell", shell.shell},
                {"connection", connectionName(shell.connection)},
                {"steps", record},
                {"ok", problem.empty()}});
    if (!problem.empty())
      throw StopRun{StopRun::kFault,
                    "connection check on shell " + std::to_string(shell.shell) + " (ball " +
                        std::to_string(shell.connection.ball_index + 1) + ", chuck " +
                        std::to_string(shell.connection.chuck_index + 1) + "): " + problem};
  }

  void launchFit(RunDir dir, std::vector<Sample> all, double set_extension_mm, int set_index) {
    if (solver.valid()) solver.wait();
    std::optional<Model> previous;
    int previous_set = 0;
    {
      std::lock_guard lock(mutex);
      if (last_result.contains("calibrated_file") && last_result.value("run", "") == dir.id()) {
        try {
          previous = loadModelFile(last_result["calibrated_file"].get<std::string>());
          previous_set = last_result.value("set", 0);
        } catch (const std::exception& e) {  // the fit goes on, without the prediction
          spdlog::warn("the previous set's model cannot be read: {}", e.what());
        }
      }
    }
    // The samples file, read as robocal solve reads it (here, while nothing appends to it): the
    // RESULT is then `robocal solve --json` of that file plus the run's keys, by construction, and
    // outliers are named by line.
    std::vector<Sample> fitted;
    try {
      fitted = loadSamplesFile(dir.file("samples.csv"));
    } catch (const std::exception& e) {
      spdlog::warn("the samples file cannot be read back for the fit: {}", e.what());
    }
    if (fitted.size() != all.size()) {
      spdlog::warn("the samples file holds {} samples, the run {}: fitting the run's",
                   fitted.size(), all.size());
      fitted = std::move(all);
    }
    solver =
        std::async(std::launch::async, [this, dir, fitted = std::move(fitted), set_extension_mm,
                                        set_index, previous, previous_set]() mutable {
          try {
            AssessOptions options;  // robocal solve's defaults
            if (previous) {
              HeldOutSamples held{{},
                                  previous,
                                  "set " + std::to_string(set_index) + " predicted by the set-" +
                                      std::to_string(previous_set) + " fit"};
              for (const Sample& s : fitted)
                if (std::abs(s.extension_mm - set_extension_mm) < 1e-6) held.samples.push_back(s);
              if (!held.samples.empty()) options.validation = std::move(held);
            }
            const FitAssessment fit = assessFit(nominal, std::move(fitted), options);
            const std::string name = "set" + std::to_string(set_index);
            const std::string model_file = dir.file("calibrated-" + name + ".json");
            const Model calibrated = calibratedModel(fit, {dir.id(), {dir.file("samples.csv")}});
            saveModelFile(model_file, calibrated);
            writeReport(dir.file("report-" + name), fit, calibrated);
            json result = fitSummaryJson(fit);
            result["run"] = dir.id();
            result["set"] = set_index;
            result["extension_mm"] = set_extension_mm;
            result["calibrated_file"] = model_file;
            result["report_dir"] = dir.file("report-" + name);
            result["samples_file"] = dir.file("samples.csv");
            if (fit.validation)  // kept for clients of protocol 1.0; validation_* say the same
              result["prediction"] = {{"n", fit.validation->stats.count},
                                      {"rms_mm", fit.validation->stats.rms_mm},
                                      {"max_abs_mm", fit.validation->stats.max_abs_mm}};
            dir.writeJson("result-" + name + ".json", result);
            dir.logEvent({{"event", "result"},
                          {"set", set_index},
                          {"rms_mm", fit.fit.after.rms_mm},
                          {"problems", fit.problems}});
            for (const std::string& problem : fit.problems)
              spdlog::warn("set {} fit not usable as a calibration: {}", set_index, problem);
            {
              std::lock_guard lock(mutex);
              last_result = result;
            }
            publish(result, false);
          } catch (const std::exception& e) {
            spdlog::error("solver failed: {}", e.what());
            publish({{"class", "ERROR"}, {"message", std::string("solver failed: ") + e.what()}},
                    false);
          }
        });
  }

  struct Measurement {
    JointsDeg joints_deg;
    double deflection_mm, spread_mm;
    std::size_t readings;
    Clock::time_point bar_window_start, where_end;
  };
  // The bar averaged over bar_window_s and the actual joints (WHERE) read within that window,
  // watched. The window opens at once: the controller's answer does not delay it.
  Measurement measureHere() { return measureHere(config.bar_window_s); }
  Measurement measureHere(double window_s) {
    struct Collecting {  // also when a fault ends the window early: nothing collects while idle
      bool& flag;
      explicit Collecting(bool& f) : flag(f) { flag = true; }
      ~Collecting() { flag = false; }
    };
    Measurement m;
    window.clear();
    const Collecting collect(collecting);
    m.bar_window_start = Clock::now();
    m.joints_deg = fromDriver(val->where().joints_deg);
    m.where_end = Clock::now();
    spinUntil(m.bar_window_start + fromSeconds(window_s), true);
    // The window may have passed while WHERE was answered: the bar is checked in any case.
    checkpoint();
    watchBar(false);
    const auto deadline = Clock::now() + fromSeconds(config.drivers.bar.stale_after_s);
    while (window.empty() && Clock::now() < deadline) spin(0.02, true);
    if (window.empty()) throw StopRun{StopRun::kFault, "no ball-bar reading to record"};
    double sum = 0, lo = window.front(), hi = window.front();
    for (double v : window) {
      sum += v;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    m.deflection_mm = sum / window.size();
    m.spread_mm = hi - lo;
    m.readings = window.size();
    return m;
  }

  void runShells(RunDir& dir, const Plan& plan) {
    const CellConfig& cell_config = cellFor(plan);
    std::vector<Sample> samples = dir.loadSamples();
    std::set<std::tuple<int, double, double>> done;
    for (const Sample& s : samples) {
      const auto [lat, lon] = pointKey(s.lat_deg, s.lon_deg);
      done.insert({s.shell, lat, lon});
    }
    int total = 0;
    for (const auto& sh : plan.shells)
      for (const auto& st : sh.steps) total += st.kind == StepKind::kPoint;
    // Time left: the plan's robot time for the points not yet measured, at the pace measured.
    TimeLeft time_left;
    const auto timeLeftSeconds = [&] {
      double planned_s = 0;
      for (const auto& sh : plan.shells) {
        int left = 0;
        for (const auto& st : sh.steps) {
          const auto [lat, lon] = pointKey(st.lat_deg, st.lon_deg);
          left += st.kind == StepKind::kPoint && !done.count({sh.shell, lat, lon});
        }
        planned_s += left * plannedPointSeconds(sh, cell_config);
      }
      return time_left.seconds(planned_s);
    };
    {
      std::lock_guard lock(mutex);
      shells_total = static_cast<int>(plan.shells.size());
    }
    updateProgress(static_cast<int>(samples.size()), total, timeLeftSeconds());

    ShellWatch shell_watch;  // a connection going bad mid-shell
    // Re-plan files are numbered on from those of the run's earlier sessions (before a resume).
    int replans = 0;
    while (std::filesystem::exists(dir.file("replans/" + std::to_string(replans + 1) + ".json")))
      ++replans;
    std::optional<Model> refined;
    // The centring fit also uses measurements that are not data points (at the connect pose,
    // after corrective moves): they tell the model's error where the robot is about to go.
    std::vector<Sample> centring = samples;
    std::size_t refined_at = 0;  // centring measurements in the last refit
    auto refit = [&] {
      refined = refine(centring, plan);
      refined_at = centring.size();
    };
    if (config.centering && !centring.empty()) refit();

    for (std::size_t si = 0; si < plan.shells.size(); ++si) {
      const ShellPlan& planned = plan.shells[si];
      const auto is_done = [&](const PlanStep& st) {
        const auto [lat, lon] = pointKey(st.lat_deg, st.lon_deg);
        return done.count({planned.shell, lat, lon}) > 0;
      };
      int remaining = 0, already = 0;
      for (const auto& st : planned.steps)
        if (st.kind == StepKind::kPoint) (is_done(st) ? already : remaining)++;
      if (remaining == 0) continue;
      const Connection c = planned.connection;
      const std::string conn = connectionName(c);
      {
        std::lock_guard lock(mutex);
        shell_number = planned.shell;
        connection_name = conn;
      }

      // A bar left attached (by the last shell, an earlier run, a pause or a crash) is detached
      // before anything moves.
      if (barMaybeAttached()) {
        waitDetach(dir, planned.shell, "Detach the ball-bar from the robot, then confirm.");
      }
      setState("moving", "to shell " + std::to_string(planned.shell) + "'s connect pose");
      JointsDeg q = move(planned.connect.joints_deg, false, false);
      waitConfirm(
          dir,
          {{"class", "PROMPT"},
           {"action", "connect"},
           {"shell", planned.shell},
           {"ball", c.ball_index + 1},
           {"chuck", c.chuck_index + 1},
           {"extension_mm", planned.extension_mm},
           {"message",
            "Connect ball " + std::to_string(c.ball_index + 1) + " to chuck " +
                std::to_string(c.chuck_index + 1) +
                (planned.extension_mm > 0
                     ? " with the " + std::to_string(static_cast<int>(planned.extension_mm)) +
                           " mm extension"
                     : " without extension") +
                ", then confirm."}},
          planned.shell, [&](double mm) {
            // The bar is not attached yet: the ball moves along the line to the chuck.
            q = move(correction(refined ? *refined : nominal, cell_config, planned, q, -mm), false,
                     false);
          });
      setAttachment({true, c.ball_index + 1, c.chuck_index + 1, planned.extension_mm, dir.id()});
      bar_offset_mm = cell_config.bar.nominal_length_mm + planned.extension_mm;
      // The bar must read, and read near zero, before anything moves with it attached.
      last_reading.reset();
      spin(std::min(1.0, config.drivers.bar.stale_after_s), false);
      if (!last_reading)
        throw StopRun{StopRun::kFault, "no ball-bar reading after connecting " + conn};
      watchBar(false);
      dir.logEvent({{"event", "connected"},
                    {"shell", planned.shell},
                    {"connection", conn},
                    {"deflection_mm", last_reading->value_mm}});
      // The model's error shows at the connect pose already: move the ball along the bar to
      // zero deflection before the shell starts.
      for (int k = 0; k < 3 && std::abs(last_reading->value_mm) > 0.5 * config.bar_soft_limit_mm;
           ++k) {
        const double d = last_reading->value_mm;
        event(
            dir,
            {{"event", "recentre"}, {"shell", planned.shell}, {"step", -1}, {"deflection_mm", d}});
        q = move(correction(refined ? *refined : nominal, cell_config, planned, q, d), true, false);
        last_reading.reset();
        spin(0.2, false);
        if (!last_reading) throw StopRun{StopRun::kFault, "no ball-bar reading after re-centring"};
        watchBar(false);
      }
      verifyConnection(dir, refined ? *refined : nominal, cell_config, planned, q);

      // A measurement as a sample of this shell (a data point adds its latitude and longitude).
      auto shellSample = [&](const Measurement& m) {
        Sample s;
        s.shell = planned.shell;
        s.ball_index = c.ball_index;
        s.chuck_index = c.chuck_index;
        s.extension_mm = planned.extension_mm;
        s.joints_deg = m.joints_deg;
        s.length_mm = bar_offset_mm + m.deflection_mm;
        return s;
      };
      if (config.centering) {
        centring.push_back(shellSample(measureHere()));
        refit();
      }

      // What is left of the shell, re-planned from here when points are done or the model is
      // refined.
      ShellPlan shell = planned;
      if (already > 0) {
        shell.steps.clear();
        for (const auto& st : planned.steps)
          if (st.kind == StepKind::kPoint && !is_done(st)) shell.steps.push_back(st);
      }
      // Re-plans the steps from `from` on, starting at `at`, with the latest model; a point that
      // is no longer safe to reach is dropped, and said so.
      auto replanFrom = [&](std::size_t from, const JointsDeg& at, const std::string& why) {
        const ShellPlanner planner(refined ? *refined : nominal, cell_config);
        const std::size_t dropped_before = shell.dropped.size();
        shell = planner.replanRemaining(shell, from, at);
        for (std::size_t k = dropped_before; k < shell.dropped.size(); ++k)
          event(dir, {{"event", "point_dropped"},
                      {"shell", planned.shell},
                      {"lat_deg", shell.dropped[k].lat_deg},
                      {"lon_deg", shell.dropped[k].lon_deg},
                      {"reason", shell.dropped[k].reason}});
        recordReplan(dir, replans, shell, from, why);
      };
      if (already > 0 || refined) replanFrom(0, q, already > 0 ? "resume" : "refined model");

      setState("measuring", "shell " + std::to_string(planned.shell) + " " + conn);
      const double point_planned_s = plannedPointSeconds(planned, cell_config);
      shell_watch.startShell();
      auto pace_mark = Clock::now();  // the operator's time at prompts is not the robot's pace
      int corrections = 0;
      std::size_t next = 0;
      while (next < shell.steps.size()) {
        const PlanStep& step = shell.steps[next];
        try {
          q = move(step.joints_deg, true, config.centering);
        } catch (const Recentre& r) {
          stopRobot();
          if (++corrections > 20)
            throw StopRun{StopRun::kFault,
                          "cannot keep the bar centred on shell " + std::to_string(planned.shell)};
          q = fromDriver(val->where().joints_deg);
          const Model& model = refined ? *refined : nominal;
          event(dir, {{"event", "recentre"},
                      {"shell", planned.shell},
                      {"step", next},
                      {"deflection_mm", r.deflection_mm}});
          q = move(correction(model, cell_config, planned, q, r.deflection_mm), true, false);
          centring.push_back(shellSample(measureHere()));
          refit();
          replanFrom(next, q, "recentre");
          continue;
        }
        if (step.kind == StepKind::kPoint) {
          PointTiming timing;
          const auto motion_end = timing.motion_complete = Clock::now();
          spinUntil(motion_end + fromSeconds(config.settle_s), true);
          const Measurement m = measureHere();
          const double dwell_s =
              std::chrono::duration<double>(m.bar_window_start - motion_end).count();
          const JointsDeg actual = m.joints_deg;
          Sample s = shellSample(m);
          s.lat_deg = step.lat_deg;
          s.lon_deg = step.lon_deg;
          dir.appendSample(s, m.spread_mm);  // on disk before the robot moves again
          timing.sample_on_disk = Clock::now();
          timing.bar_window_start = m.bar_window_start;
          timing.where_end = m.where_end;
          dir.logEvent(timing.toEvent(s.shell, s.lat_deg, s.lon_deg, config.settle_s));
          reportLinkFaults(dir);
          samples.push_back(s);
          centring.push_back(s);
          const auto [lat, lon] = pointKey(s.lat_deg, s.lon_deg);
          done.insert({s.shell, lat, lon});
          publish({{"class", "SAMPLE"},
                   {"shell", s.shell},
                   {"lat_deg", s.lat_deg},
                   {"lon_deg", s.lon_deg},
                   {"joints", std::vector<double>(actual.data(), actual.data() + 6)},
                   {"length_mm", s.length_mm},
                   {"spread_mm", m.spread_mm},
                   {"readings", m.readings},
                   {"dwell_s", dwell_s}},
                  false);
          const auto now = Clock::now();
          time_left.pointMeasured(point_planned_s,
                                  std::chrono::duration<double>(now - pace_mark).count());
          pace_mark = now;
          updateProgress(static_cast<int>(samples.size()), total, timeLeftSeconds());
          if (const std::string suspect = shell_watch.point(m.deflection_mm, m.spread_mm);
              !suspect.empty())
            throw StopRun{StopRun::kFault,
                          "shell " + std::to_string(planned.shell) + " " + conn + ": " + suspect +
                              ": check that ball " + std::to_string(c.ball_index + 1) +
                              " is tight in its socket and the bar sits in chuck " +
                              std::to_string(c.chuck_index + 1) + ", then resume"};
          // Refit as the data grow by 5% (every sample at first): a fit costs milliseconds
          // that grow with the samples, and a model from a few more samples changes little.
          if (config.centering && next + 1 < shell.steps.size() &&
              centring.size() >= refined_at + 1 + refined_at / 20) {
            refit();
            replanFrom(next + 1, actual, "refined model");
          }
        }
        ++next;
      }
      // A shell set is complete when no later shell has the same extension.
      bool set_complete = true;
      for (std::size_t k = si + 1; k < plan.shells.size(); ++k)
        if (plan.shells[k].extension_mm == planned.extension_mm) set_complete = false;
      if (set_complete) {
        int set_index = 1;
        std::vector<double> seen;
        for (const auto& sh : plan.shells) {
          if (std::find(seen.begin(), seen.end(), sh.extension_mm) == seen.end())
            seen.push_back(sh.extension_mm);
          if (sh.extension_mm == planned.extension_mm) break;
        }
        set_index = static_cast<int>(seen.size());
        event(dir, {{"event", "set_complete"},
                    {"set", set_index},
                    {"extension_mm", planned.extension_mm}});
        launchFit(dir, samples, planned.extension_mm, set_index);
      }
    }
    // The run ends with the bar off the robot: the next run must not move with it attached.
    if (barMaybeAttached())
      waitDetach(dir, 0, "The run is complete: detach the ball-bar from the robot, then confirm.");
  }

  // Asks the operator to detach the bar (shell 0: at the end of the run) and records, once
  // confirmed, that it is off the robot.
  void waitDetach(RunDir& dir, int shell, const std::string& message) {
    bar_offset_mm = 0;
    const BarAttachment was = attachmentNow();
    json prompt_object = {
        {"class", "PROMPT"}, {"action", "detach"}, {"shell", shell}, {"message", message}};
    if (was.ball > 0) {
      prompt_object["ball"] = was.ball;
      prompt_object["chuck"] = was.chuck;
      prompt_object["extension_mm"] = was.extension_mm;
    }
    waitConfirm(dir, prompt_object, shell);
    setAttachment({});
  }

  void execute(Job job) {
    abort_requested = false;
    pause_requested = false;
    link_faults_reported = linkFaultCounts();  // what happened between runs is not this run's
    {
      std::lock_guard lock(mutex);
      stop_reason.clear();
    }
    std::optional<RunDir> dir;
    try {
      Plan plan = job.plan;
      if (job.kind == Job::kStart) {
        // A port that went away since `start` was accepted: no run is made for nothing.
        try {
          ensureDevices();
        } catch (const StopRun& stop) {
          publish(proto::errorObject("run not started: " + stop.reason, "start"), false);
          setState("error", "run not started: " + stop.reason);
          return;
        }
        dir = store.create(formatPlan(plan));
      } else {
        dir = store.open(job.run_id);
        plan = parsePlan(readTextFile(dir->file("plan.json")), dir->file("plan.json"));
      }
      {
        std::lock_guard lock(mutex);
        run_id = dir->id();
        resumable_id.clear();
      }
      dir->setState({{"status", "running"}});
      dir->logEvent({{"event", job.kind == Job::kStart ? "start" : "resume"}});
      setState("checking", "run " + dir->id() + ": checking the plan");
      const auto violations = checkPlan(nominal, cellFor(plan), plan);
      if (!violations.empty()) {
        json list = json::array();
        for (const auto& v : violations) list.push_back(describeViolation(v));
        dir->logEvent({{"event", "plan_rejected"}, {"violations", list}});
        dir->setState({{"status", "aborted"}, {"reason", "plan failed the safety check"}});
        publish({{"class", "ERROR"},
                 {"message", std::to_string(violations.size()) +
                                 " safety violations in the plan; nothing moved"},
                 {"violations", list}},
                false);
        setState("error", "plan failed the safety check: " + describeViolation(violations.front()));
        return;
      }
      ensureDevices();
      runShells(*dir, plan);
      reportLinkFaults(*dir);
      dir->setState({{"status", "done"}});
      dir->logEvent({{"event", "done"}});
      setState("solving", "waiting for the last fit");
      if (solver.valid()) solver.wait();
      setState("done", "run " + dir->id() + " complete");
    } catch (const StopRun& stop) {
      stopRobot();
      handleStop(dir, stop);
    } catch (const Recentre&) {
      stopRobot();
      handleStop(dir, {StopRun::kFault, "bar past the soft limit"});
    } catch (const drivers::DriverError& e) {
      stopRobot();
      handleStop(dir, {StopRun::kFault, e.what()});
    } catch (const std::exception& e) {
      stopRobot();
      handleStop(dir, {StopRun::kFault, std::string("error: ") + e.what()});
    }
    std::lock_guard lock(mutex);
    prompt = nullptr;
  }

  void handleStop(std::optional<RunDir>& dir, const StopRun& stop) {
    bar_offset_mm = 0;
    const bool aborted = stop.kind == StopRun::kAbort;
    const std::string status = aborted ? "aborted" : "paused";
    if (dir) {
      try {
        reportLinkFaults(*dir);
        dir->setState({{"status", status}, {"reason", stop.reason}});
        dir->logEvent({{"event", status}, {"reason", stop.reason}});
      } catch (const std::exception& e) {
        spdlog::error("cannot record the stop: {}", e.what());
      }
      if (!aborted) {
        std::lock_guard lock(mutex);
        resumable_id = dir->id();
      }
    }
    spdlog::warn("run {}: {}", status, stop.reason);
    setState(status, stop.reason + (aborted ? "" : "; the robot is stopped, resume continues"));
  }

  void threadMain() {
    auto next_connect = Clock::now();
    while (!quit) {
      std::optional<Job> todo;
      {
        std::unique_lock lock(mutex);
        if (job) {
          todo = std::move(job);
          job.reset();
        }
      }
      if (todo) {
        execute(std::move(*todo));
        continue;
      }
      // Idle: keep the bar streaming to watchers and both ports ready, reconnecting now and then.
      if (Clock::now() >= next_connect &&
          (!bar || !bar->isConnected() || !val || !val->isConnected())) {
        next_connect = Clock::now() + std::chrono::seconds(2);
        connectDevices();
      }
      io.restart();
      io.run_for(std::chrono::milliseconds(20));
      if (io.stopped()) {
        std::unique_lock lock(mutex);
        wake.wait_for(lock, std::chrono::milliseconds(20));
      }
    }
  }

  json statusObject() const {
    std::lock_guard lock(mutex);
    json s = {{"class", "STATUS"},
              {"state", state},
              {"reason", state_reason},
              {"run", run_id},
              {"shell", shell_number},
              {"shells", shells_total},
              {"points_done", points_done},
              {"points_total", points_total},
              {"eta_s", eta_s},
              {"connection", connection_name},
              {"bar_attached", attachment.maybe_attached},
              {"devices", {{"val", val_connected}, {"bar", bar_connected}}}};
    if (!val_error.empty()) s["devices"]["val_error"] = val_error;
    if (!bar_error.empty()) s["devices"]["bar_error"] = bar_error;
    // Every field is always there: null (or "") when there is nothing.
    s["resumable"] = resumable_id;
    s["prompt"] = prompt;
    s["bar"] = latest_bar;
    return s;
  }
};

RunController::RunController(DaemonConfig config, Model nominal, std::optional<CellConfig> cell,
                             Publish publish)
    : impl_(std::make_unique<Impl>(std::move(config), std::move(nominal), std::move(cell),
                                   std::move(publish))) {}

RunController::~RunController() = default;

namespace {
bool busy(const std::string& state) {
  return state == "checking" || state == "moving" || state == "awaiting_confirm" ||
         state == "measuring";
}
}  // namespace

std::string RunController::start(const Plan& plan) {
  std::lock_guard lock(impl_->mutex);
  if (busy(impl_->state) || impl_->job) return "a run is in progress (" + impl_->state + ")";
  if (!impl_->resumable_id.empty() && impl_->state != "done")
    return "run " + impl_->resumable_id + " is " + impl_->state +
           ": resume it or abort it before starting another";
  // Refused before a run folder exists: a missing port leaves no empty run in the history.
  if (!impl_->bar_connected)
    return "the ball-bar reader is not connected: " + impl_->bar_error +
           " (robocald retries every 2 s; `robocal probe --bar PORT` checks the port)";
  if (!impl_->val_connected)
    return "the VAL II controller is not connected: " + impl_->val_error +
           " (robocald retries every 2 s; `robocal probe --val PORT` checks the port)";
  impl_->job = Impl::Job{Impl::Job::kStart, plan, {}};
  impl_->wake.notify_all();
  return {};
}

std::string RunController::confirm(std::optional<int> shell) {
  std::lock_guard lock(impl_->mutex);
  if (impl_->prompt.is_null()) return "nothing to confirm: no prompt is pending";
  if (shell && *shell != impl_->prompt_shell)
    return "the pending prompt is for shell " + std::to_string(impl_->prompt_shell) + ", not " +
           std::to_string(*shell);
  ++impl_->confirms;
  return {};
}

std::string RunController::nudge(std::optional<int> shell, double mm) {
  std::lock_guard lock(impl_->mutex);
  if (impl_->prompt.is_null() || impl_->prompt.value("action", "") != "connect")
    return "nothing to nudge: no connect prompt is pending";
  if (shell && *shell != impl_->prompt_shell)
    return "the pending prompt is for shell " + std::to_string(impl_->prompt_shell);
  if (std::abs(mm) > 5.0) return "a nudge moves at most 5 mm";
  if (std::abs(impl_->nudged_mm + mm) > 10.0)
    return "nudges for this connection would pass 10 mm in all: check the set-up";
  if (impl_->nudge_mm) return "a nudge is still moving";
  impl_->nudge_mm = mm;
  impl_->nudged_mm += mm;
  return {};
}

std::string RunController::pause(const std::string& reason) {
  std::lock_guard lock(impl_->mutex);
  if (!busy(impl_->state)) return "no run is in progress (" + impl_->state + ")";
  impl_->stop_reason = reason.empty() ? "paused by the operator" : "paused: " + reason;
  impl_->pause_requested = true;
  return {};
}

std::string RunController::resume(const std::string& run_id) {
  std::lock_guard lock(impl_->mutex);
  if (busy(impl_->state) || impl_->job) return "a run is in progress (" + impl_->state + ")";
  const std::string id = run_id.empty() ? impl_->resumable_id : run_id;
  if (id.empty()) return "no paused or interrupted run to resume";
  try {
    const std::string status = impl_->store.open(id).state().value("status", "interrupted");
    if (status == "done" || status == "aborted") return "run " + id + " is " + status;
  } catch (const std::exception& e) {
    return e.what();
  }
  impl_->job = Impl::Job{Impl::Job::kResume, {}, id};
  impl_->wake.notify_all();
  return {};
}

RunController::Answer RunController::abort(const std::string& reason) {
  std::lock_guard lock(impl_->mutex);
  const bool running = busy(impl_->state) || impl_->job;
  if (!running && impl_->resumable_id.empty())
    return {"nothing to abort: no run is in progress, paused or interrupted (" + impl_->state + ")",
            {}};
  impl_->stop_reason = reason.empty() ? "aborted by the operator" : "aborted: " + reason;
  impl_->abort_requested = true;
  if (running)
    return {{}, "stopping the robot; run " + impl_->run_id + " is aborted (" + impl_->state + ")"};
  {
    // A paused or interrupted run: close it for good.
    try {
      RunDir dir = impl_->store.open(impl_->resumable_id);
      dir.setState({{"status", "aborted"}, {"reason", impl_->stop_reason}});
      dir.logEvent({{"event", "aborted"}, {"reason", impl_->stop_reason}});
    } catch (const std::exception& e) {
      return {e.what(), {}};
    }
    const std::string closed = impl_->resumable_id, was = impl_->state;
    impl_->resumable_id.clear();
    impl_->abort_requested = false;
    impl_->state = "aborted";
    impl_->state_reason = impl_->stop_reason;
    // Watchers learn it like any other change (the run thread is idle: it publishes nothing).
    impl_->publish({{"class", "STATE"},
                    {"from", was},
                    {"to", "aborted"},
                    {"reason", "run " + closed + " closed: " + impl_->stop_reason}},
                   false);
    return {{}, "run " + closed + " (" + was + ") is closed; nothing was moving"};
  }
}

nlohmann::json RunController::status() const {
  return impl_->statusObject();
}

nlohmann::json RunController::result() const {
  std::lock_guard lock(impl_->mutex);
  if (impl_->last_result.is_null())
    return {{"class", "RESULT"}, {"available", false}, {"message", "no fit yet"}};
  return impl_->last_result;
}

nlohmann::json RunController::runs() const {
  json list = json::array();
  for (const std::string& id : impl_->store.ids()) {
    const json st = impl_->store.open(id).state();
    list.push_back(
        {{"run", id}, {"status", st.value("status", "?")}, {"reason", st.value("reason", "")}});
  }
  return {{"class", "RUNS"}, {"runs", list}};
}

}  // namespace robocal::daemon
