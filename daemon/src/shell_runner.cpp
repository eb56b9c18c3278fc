#include "shell_runner.hpp"

#include <robocal/daemon/connection_check.hpp>
#include <robocal/planner/check.hpp>

#include <spdlog/spdlog.h>
#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>

namespace robocal::daemon {
namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

// A connect reading is first checked for a reading at all (over range, silent: a fault), not for
// its size; re-centring from it may go this much past where it started before it stops.
constexpr double kNoLimitMm = std::numeric_limits<double>::infinity();
constexpr double kConnectSlackMm = 0.1;
// The connection check's smallest approach step (deg): a real arm's backlash is 0.005-0.02 deg
// (docs/realism.md).
constexpr double kCheckApproachDeg = 0.02;

// A data point of a shell, as the samples file identifies it.
std::tuple<int, double, double> pointKey(int shell, double lat_deg, double lon_deg) {
  return {shell, std::round(lat_deg * 1e3) / 1e3, std::round(lon_deg * 1e3) / 1e3};
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
  // `dwell_mode` as this point's dwell was (an adaptive dwell is fixed without a noise to judge
  // by or once its audits failed); `steady`: an adaptive dwell ended by steady readings before
  // settle_s (settle_error_ms is then negative: the time saved).
  json toEvent(int shell, double lat_deg, double lon_deg, double settle_s,
               const std::string& dwell_mode, bool steady) const {
    const double settle_achieved_ms = msBetween(motion_complete, bar_window_start);
    return {{"event", "timing"},
            {"shell", shell},
            {"lat_deg", lat_deg},
            {"lon_deg", lon_deg},
            {"settle_s", settle_s},
            {"dwell_mode", dwell_mode},
            {"steady", steady},
            {"settle_achieved_ms", settle_achieved_ms},
            {"settle_error_ms", toMicrosecond(settle_achieved_ms - settle_s * 1e3)},
            {"where_ms", msBetween(bar_window_start, where_end)},
            {"motion_to_disk_ms", msBetween(motion_complete, sample_on_disk)}};
  }
};

std::string connectMessage(const ShellPlan& shell) {
  const Connection& c = shell.connection;
  return "Connect ball " + std::to_string(c.ball_index + 1) + " to chuck " +
         std::to_string(c.chuck_index + 1) +
         (shell.extension_mm > 0
              ? " with the " + std::to_string(static_cast<int>(shell.extension_mm)) +
                    " mm extension"
              : " without extension") +
         ", then confirm.";
}

}  // namespace

namespace {

CellConfig movingAsPlanned(CellConfig cell, const Plan& plan) {
  cell.motion.through_vias = plan.cell.motion.through_vias;
  cell.motion.blend_deg = plan.cell.motion.blend_deg;
  return cell;
}

}  // namespace

ShellRunner::ShellRunner(RunContext& ctx, FitJob& fits, RunDir& dir, const Plan& plan)
    : ctx_(ctx),
      fits_(fits),
      dir_(dir),
      plan_(plan),
      cell_(movingAsPlanned(ctx.cellFor(plan), plan)),
      samples_(dir.loadSamples()),
      shell_watch_(ctx.config.bar_soft_limit_mm),
      centring_(ctx.nominal, cell_, ctx.config.centering, samples_) {
  for (const Sample& s : samples_) done_.insert(pointKey(s.shell, s.lat_deg, s.lon_deg));
  for (const auto& sh : plan_.shells)
    for (const auto& st : sh.steps) total_points_ += st.kind == StepKind::kPoint;
  while (std::filesystem::exists(dir_.file("replans/" + std::to_string(replans_ + 1) + ".json")))
    ++replans_;
  ctx_.resetAdaptiveDwell();  // what a run measured of the bar's noise does not carry to the next
}

// ------------------------------------------------------------------------ book-keeping

bool ShellRunner::isDone(int shell, const PlanStep& step) const {
  return done_.count(pointKey(shell, step.lat_deg, step.lon_deg)) >
         static_cast<std::size_t>(step.visit);
}

int ShellRunner::pointsLeft(const ShellPlan& shell) const {
  int left = 0;
  for (const auto& st : shell.steps)
    left += st.kind == StepKind::kPoint && !isDone(shell.shell, st);
  return left;
}

double ShellRunner::plannedPointSeconds(const ShellPlan& shell) const {
  const ShellSummary& s = shell.summary;
  if (s.points <= 0) return 0;
  const double moves_s = std::max(0.0, s.duration_s - s.points * cell_.motion.settle_s);
  return moves_s / s.points + ctx_.config.settle_s + ctx_.config.bar_window_s;
}

double ShellRunner::timeLeftSeconds() const {
  double planned_s = 0;
  for (const auto& sh : plan_.shells) planned_s += pointsLeft(sh) * plannedPointSeconds(sh);
  return time_left_.seconds(planned_s);
}

void ShellRunner::progress() {
  ctx_.updateProgress(static_cast<int>(samples_.size()), total_points_, timeLeftSeconds());
}

Sample ShellRunner::shellSample(const ShellPlan& shell, const RunContext::Measurement& m) const {
  // Not a data point (lat/lon 0) unless the caller sets them.
  return makeSample(shell.shell, shell.connection, shell.extension_mm, 0, 0, m.joints_deg,
                    ctx_.barOffset() + m.deflection_mm);
}

// ------------------------------------------------------------------------ the run

void ShellRunner::run() {
  ctx_.shared.with([&](RunData& d) { d.shells_total = static_cast<int>(plan_.shells.size()); });
  progress();
  for (std::size_t si = 0; si < plan_.shells.size(); ++si) {
    const ShellPlan& shell = plan_.shells[si];
    const int left = pointsLeft(shell);
    if (left == 0) {
      // Measured in an earlier session: its set's fit may have been cut short by a kill.
      completeSet(si, true);
      continue;
    }
    int points = 0;
    for (const auto& st : shell.steps) points += st.kind == StepKind::kPoint;
    ctx_.shared.with([&](RunData& d) {
      d.shell_number = shell.shell;
      d.connection_name = connectionName(shell.connection);
    });
    const JointsDeg q = connect(shell);
    measure(shell, points - left, q);
    completeSet(si);
  }
  // The run ends with the bar off the robot: the next run must not move with it attached.
  if (ctx_.barMaybeAttached())
    detach(0, "The run is complete: detach the ball-bar from the robot, then confirm.");
}

JointsDeg ShellRunner::corrected(const ShellPlan& shell, const JointsDeg& q,
                                 double deflection_mm) const {
  std::string problem;
  if (auto target = correction(centring_.model(), cell_, shell, q, deflection_mm, problem))
    return *target;
  throw StopRun{StopRun::kFault, "corrective move of " + std::to_string(deflection_mm) +
                                     " mm on shell " + std::to_string(shell.shell) +
                                     " refused: " + problem};
}

void ShellRunner::detach(int shell_number, const std::string& message) {
  const BarAttachment was = ctx_.attachment();
  ctx_.waitDetach(dir_, shell_number, message);
  if (was.ball < 1 || was.chuck < 1) return;  // no line to probe along: an unknown connection
  // Away from the chuck by twice the threshold (an attached bar shows it, a free one does not),
  // and never more than half the hard limit: an attached bar stays well inside its range.
  const double probe_mm =
      std::min(2 * ctx_.config.detached_change_mm, 0.5 * ctx_.config.bar_hard_limit_mm);
  ShellPlan along;
  along.shell = shell_number;
  along.connection = {was.ball - 1, was.chuck - 1};
  along.extension_mm = was.extension_mm;
  const JointsDeg q = ctx_.io.where();
  std::string problem;
  const auto away = correction(centring_.model(), cell_, along, q, -probe_mm, problem);
  if (!away) {
    ctx_.event(dir_, {{"event", "detach_probe"}, {"shell", shell_number}, {"skipped", problem}});
    return;
  }
  const RunContext::Followed f = ctx_.moveWatchingForBar(
      *away, ctx_.recentReadingMm(), std::max(0.3, 3 * ctx_.config.bar_window_s));
  ctx_.event(dir_, {{"event", "detach_probe"},
                    {"shell", shell_number},
                    {"moved_mm", probe_mm},
                    {"reading_change_mm", f.change_mm},
                    {"over_range", f.over_range}});
  if (!f.followed) return;
  BarAttachment doubt = was;
  doubt.maybe_attached = true;
  ctx_.setAttachment(doubt);  // the resume asks to detach it again
  char buf[160];
  std::snprintf(buf, sizeof buf, f.over_range ? "went over range" : "changed by %+.3f mm",
                f.change_mm);
  throw StopRun{StopRun::kFault,
                "the ball-bar reading " + std::string(buf) + " when the ball moved " +
                    std::to_string(probe_mm).substr(0, 4) + " mm away from chuck " +
                    std::to_string(was.chuck) +
                    " after the detach: the bar is still on the robot. Take it off ball " +
                    std::to_string(was.ball) + ", then resume (the detach is asked again)"};
}

JointsDeg ShellRunner::nudge(const ShellPlan& shell, JointsDeg q, double mm) {
  // The bar should not be attached yet: the ball creeps along the line to the chuck in steps of
  // the detached threshold, and stops at the first step the bar follows (it was seated after
  // all: a whole nudge at the controller's speed would stretch or crush it).
  const double threshold_mm = ctx_.config.detached_change_mm;
  const std::optional<double> free_mm = ctx_.recentReadingMm();
  const int steps = std::max(1, static_cast<int>(std::ceil(std::abs(mm) / threshold_mm)));
  for (int k = 1; k <= steps; ++k) {
    const RunContext::Followed f = ctx_.moveWatchingForBar(
        corrected(shell, q, -mm / steps), free_mm, std::max(0.1, ctx_.config.bar_window_s));
    q = f.joints_deg;
    if (!f.followed) continue;
    ctx_.event(dir_, {{"event", "nudge_stopped"},
                      {"shell", shell.shell},
                      {"mm", mm},
                      {"moved_mm", mm * k / steps},
                      {"reading_change_mm", f.change_mm},
                      {"over_range", f.over_range},
                      {"reason",
                       "the bar follows the ball: it is seated. Confirm if it is "
                       "seated where it should be; take it off the ball to nudge"}});
    break;
  }
  return q;
}

JointsDeg ShellRunner::connect(const ShellPlan& shell) {
  const Connection& c = shell.connection;
  const std::string conn = connectionName(c);
  // A bar left attached (by the last shell, an earlier run, a pause or a crash) is detached
  // before anything moves.
  if (ctx_.barMaybeAttached())
    detach(shell.shell, "Detach the ball-bar from the robot, then confirm.");
  ctx_.setState(proto::RunState::kMoving,
                "to shell " + std::to_string(shell.shell) + "'s connect pose");
  JointsDeg q = ctx_.move(shell.connect.joints_deg, false);
  // From the connect prompt on, the operator may seat the bar at any moment: a stop or a crash
  // before the confirm (the daemon killed between the seating and the confirm) must still ask to
  // detach it before anything moves. Recording it only at the confirm let a resume move the robot
  // back from a nudged pose with the bar seated (found by the kill -9 test: the bar went over
  // range).
  ctx_.setAttachment({true, c.ball_index + 1, c.chuck_index + 1, shell.extension_mm, dir_.id()});
  ctx_.waitConfirm(dir_,
                   proto::Prompt{proto::PromptAction::kConnect, shell.shell, c.ball_index + 1,
                                 c.chuck_index + 1, shell.extension_mm, connectMessage(shell)},
                   [&](double mm) { q = nudge(shell, q, mm); });
  ctx_.setBarOffset(cell_.bar.nominal_length_mm + shell.extension_mm);
  // The bar must read, and read near zero, before anything moves with it attached.
  ctx_.forgetReading();
  ctx_.spin(std::min(1.0, ctx_.config.drivers.bar.stale_after_s), false);
  if (!ctx_.lastReading())
    throw StopRun{StopRun::kFault, "no ball-bar reading after connecting " + conn};
  // A connect reading past the hard limit but inside the bar's range is the model's error at the
  // connect pose (a robot 2 mm off its model): the ball is moved back along the bar, watched
  // against the reading it starts from, instead of pausing a run that a resume would only bring
  // back here. Over range, or silent, stops as always.
  ctx_.watchBar(kNoLimitMm);
  const double connect_limit_mm =
      std::max(ctx_.config.bar_hard_limit_mm,
               std::min(cell_.bar.max_deflection_mm,
                        std::abs(ctx_.lastReading()->value_mm) + kConnectSlackMm));
  dir_.logEvent({{"event", "connected"},
                 {"shell", shell.shell},
                 {"connection", conn},
                 {"deflection_mm", ctx_.lastReading()->value_mm}});
  // The model's error shows at the connect pose already: move the ball along the bar to zero
  // deflection before the shell starts.
  for (int k = 0;
       k < 3 && std::abs(ctx_.lastReading()->value_mm) > 0.5 * ctx_.config.bar_soft_limit_mm; ++k) {
    const double d = ctx_.lastReading()->value_mm;
    ctx_.event(dir_,
               {{"event", "recentre"}, {"shell", shell.shell}, {"step", -1}, {"deflection_mm", d}});
    q = ctx_.move(corrected(shell, q, d), true, connect_limit_mm);
    ctx_.forgetReading();
    ctx_.spin(0.2, false);
    if (!ctx_.lastReading())
      throw StopRun{StopRun::kFault, "no ball-bar reading after re-centring"};
    ctx_.watchBar(connect_limit_mm);
  }
  ctx_.watchBar();  // from here on the run's own limits
  verifyConnection(shell, q);
  if (centring_.enabled()) {
    centring_.add(shellSample(shell, ctx_.measureHere()));
    centring_.refit();
  }
  return q;
}

void ShellRunner::verifyConnection(const ShellPlan& shell, JointsDeg& q) {
  const DaemonConfig& config = ctx_.config;
  const double step_mm = std::min(config.connection_check_mm, 0.4 * config.bar_soft_limit_mm);
  if (step_mm <= 0) return;
  // Averaged over at least half a second: the steps are tenths of a millimetre, the noise of
  // one reading a few hundredths.
  // Read with the robot still after a full settle_s, these windows also measure the bar's noise
  // for the adaptive dwell (afresh at each connection: the bar is seated anew).
  ctx_.forgetStillNoise();
  const auto settledMeasurement = [&] {
    ctx_.spin(config.settle_s, true);
    const RunContext::Measurement m = ctx_.measureHere(std::max(config.bar_window_s, 0.5));
    ctx_.noteStillWindow(m);
    return m;
  };
  const JointsDeg start = q;
  // Every pose the check reads is reached up in every joint from a pre-point (kCheckApproachDeg),
  // so that each joint's backlash sits on the same side at every reading: a real arm's 0.01 deg
  // of it, taken from both sides, changed a correct bar's reading by 0.07 mm across the bar and
  // failed the check. The pre-point keeps the bar's length (one joint steps back further, as the
  // planner's approach does: the plain step changed it by 0.3 mm at the main job's connect pose
  // and was skipped). Where no joint can undo the step (every joint's step back shortens the bar,
  // as at the top of a shell) and the pre-point would change the bar by more than the check's own
  // step (step_mm, which the check commands anyway), the joints step back and up a group at a time
  // (approachStages: a big arm's 0.02 deg moved an RX160's ball 0.67 mm, and the check skipped
  // its pre-point and failed a correct bar on backlash). Pre-points outside the joint limits are
  // not taken: the check then reads that pose as it comes. The log says when either happens.
  bool logged = false;
  const Model& model = centring_.model();
  const Kinematics kin(model);
  const auto moveUpTo = [&](const JointsDeg& target) {
    std::vector<int> left_out;
    std::vector<JointsDeg> stages = approachStages(kin, model.balls_mm[shell.connection.ball_index],
                                                   model.chucks_mm[shell.connection.chuck_index],
                                                   target, kCheckApproachDeg, step_mm, left_out);
    bool inside = true;
    for (const JointsDeg& pre : stages)
      for (int j = 0; j < kJointCount; ++j) inside = inside && pre[j] >= model.joints[j].min_deg;
    if (!inside) stages.clear();
    if (!logged && (stages.size() != 1 || !left_out.empty())) {
      logged = true;
      json left_out_joints = json::array();
      for (int j : left_out) left_out_joints.push_back(j + 1);
      ctx_.event(dir_,
                 {{"event", stages.empty() ? "check_pre_point_skipped" : "check_pre_point_staged"},
                  {"shell", shell.shell},
                  {"stages", stages.size()},
                  {"left_out_joints", left_out_joints},
                  {"inside_limits", inside}});
    }
    for (const JointsDeg& pre : stages) {
      ctx_.move(pre, true);
      ctx_.move(target, true);
    }
    return ctx_.move(target, true);
  };
  // Every step goes from a commanded pose to a commanded pose, and the model predicts the change
  // between them: the joints WHERE reports are rounded (0.01 deg is 0.05 mm at the ball), and a
  // step planned from them moved the ball by that much more than predicted.
  JointsDeg commanded = q;
  moveUpTo(commanded);
  double before_mm = settledMeasurement().deflection_mm;
  const Connection& c = shell.connection;
  std::vector<ProbeStep> steps;
  json record = json::array();
  std::string problem;  // the first step that fails ends the check: a wrong bar moves no more
  const auto probe = [&](const Eigen::Vector3d& move_mm, double along_mm, double across_mm) {
    if (!problem.empty()) return;
    std::string refused;
    const auto target = ballMove(model, cell_, shell, commanded, move_mm, refused);
    if (!target)
      throw StopRun{StopRun::kFault, "connection check on shell " + std::to_string(shell.shell) +
                                         ": its step is refused: " + refused};
    const double predicted_mm = barLengthMm(model, c, *target) - barLengthMm(model, c, commanded);
    q = moveUpTo(*target);
    commanded = *target;
    const double after_mm = settledMeasurement().deflection_mm;
    steps.push_back({along_mm, after_mm - before_mm, across_mm, predicted_mm});
    record.push_back({{"commanded_mm", along_mm},
                      {"across_mm", across_mm},
                      {"predicted_mm", predicted_mm},
                      {"reading_change_mm", after_mm - before_mm}});
    before_mm = after_mm;
    problem = connectionCheckProblem(steps);
  };
  // Along the bar, toward zero first: the bar stays inside its soft limit all the way.
  const double sign = before_mm > 0 ? -1.0 : 1.0;
  for (const double along_mm : {sign * step_mm, -2.0 * sign * step_mm})
    probe(along_mm * barDirection(model, c, commanded), along_mm, 0);
  // Across it, two ways at right angles, each out and back: a bar on another ball turns.
  const Eigen::Vector3d u = barDirection(model, c, commanded);
  Eigen::Vector3d w1 = u.cross(Eigen::Vector3d::UnitZ());
  if (w1.norm() < 0.3) w1 = u.cross(Eigen::Vector3d::UnitX());
  w1.normalize();
  const Eigen::Vector3d w2 = u.cross(w1).normalized();
  for (const Eigen::Vector3d& w : {w1, w2}) {
    probe(step_mm * w, 0, step_mm);
    probe(-step_mm * w, 0, -step_mm);
  }
  q = ctx_.move(start, true);
  ctx_.event(dir_, {{"event", "connection_check"},
                    {"shell", shell.shell},
                    {"connection", connectionName(shell.connection)},
                    {"steps", record},
                    {"still_noise_mm", ctx_.stillNoise().mm()},
                    {"ok", problem.empty()}});
  if (!problem.empty())
    throw StopRun{StopRun::kFault,
                  "connection check on shell " + std::to_string(shell.shell) + " (ball " +
                      std::to_string(shell.connection.ball_index + 1) + ", chuck " +
                      std::to_string(shell.connection.chuck_index + 1) + "): " + problem};
}

void ShellRunner::replanFrom(ShellPlan& shell, std::size_t from, const JointsDeg& at,
                             const std::string& why) {
  const ShellPlanner planner(centring_.model(), cell_);
  const std::size_t dropped_before = shell.dropped.size();
  shell = planner.replanRemaining(shell, from, at);
  for (std::size_t k = dropped_before; k < shell.dropped.size(); ++k)
    ctx_.event(dir_, {{"event", "point_dropped"},
                      {"shell", shell.shell},
                      {"lat_deg", shell.dropped[k].lat_deg},
                      {"lon_deg", shell.dropped[k].lon_deg},
                      {"reason", shell.dropped[k].reason}});
  ++replans_;
  json steps = json::array();
  for (std::size_t i = from; i < shell.steps.size(); ++i) {
    const auto& s = shell.steps[i];
    steps.push_back({{"kind", s.kind == StepKind::kPoint ? "point" : "via"},
                     {"joints", std::vector<double>(s.joints_deg.data(), s.joints_deg.data() + 6)},
                     {"lat_deg", s.lat_deg},
                     {"lon_deg", s.lon_deg},
                     {"visit", s.visit},
                     {"stop", stopsAt(cell_.motion, s)}});
  }
  const std::string file = "replans/" + std::to_string(replans_) + ".json";
  std::filesystem::create_directories(dir_.file("replans"));
  dir_.writeJson(file,
                 {{"shell", shell.shell}, {"from_step", from}, {"why", why}, {"steps", steps}});
  ctx_.event(dir_, {{"event", "replan"},  // to watchers too: /metrics counts it
                    {"shell", shell.shell},
                    {"from_step", from},
                    {"why", why},
                    {"file", file}});
}

void ShellRunner::measure(const ShellPlan& planned, int already, JointsDeg q) {
  // What is left of the shell, re-planned from here when points are done or the model is refined.
  ShellPlan shell = planned;
  if (already > 0) {
    shell.steps.clear();
    for (const auto& st : planned.steps)
      if (st.kind == StepKind::kPoint && !isDone(planned.shell, st)) shell.steps.push_back(st);
  }
  if (already > 0 || centring_.refined())
    replanFrom(shell, 0, q, already > 0 ? "resume" : "refined model");

  ctx_.setState(proto::RunState::kMeasuring, "shell " + std::to_string(planned.shell) + " " +
                                                 connectionName(planned.connection));
  const double point_planned_s = plannedPointSeconds(planned);
  shell_watch_.startShell();
  pace_mark_ = Clock::now();  // the operator's time at prompts is not the robot's pace
  int corrections = 0;
  std::size_t next = 0;
  while (next < shell.steps.size()) {
    // The steps up to where the arm stops: this one, or, moving through vias, the next point.
    const Stretch stretch = stretchFrom(cell_.motion, shell.steps, next);
    const std::vector<JointsDeg>& path = stretch.joints_deg;
    const std::size_t stop = stretch.last;
    const PlanStep& step = shell.steps[stop];
    if (ctx_.config.centering) {
      const RunContext::Moved moved = ctx_.moveRecentring(path);
      q = moved.joints_deg;
      if (moved.recentre_mm) {
        if (++corrections > 20)
          throw StopRun{StopRun::kFault,
                        "cannot keep the bar centred on shell " + std::to_string(planned.shell)};
        ctx_.event(dir_, {{"event", "recentre"},
                          {"shell", planned.shell},
                          {"step", next},
                          {"deflection_mm", *moved.recentre_mm}});
        q = ctx_.move(corrected(planned, q, *moved.recentre_mm), true);
        centring_.add(shellSample(planned, ctx_.measureHere()));
        centring_.refit();
        replanFrom(shell, next, q, "recentre");
        continue;
      }
    } else {
      q = ctx_.moveThrough(path);
    }
    next = stop;
    if (step.kind == StepKind::kPoint) {
      const JointsDeg actual = recordPoint(planned, step, point_planned_s);
      if (next + 1 < shell.steps.size() && centring_.refitDue()) {
        centring_.refit();
        replanFrom(shell, next + 1, actual, "refined model");
      }
    }
    ++next;
  }
}

JointsDeg ShellRunner::recordPoint(const ShellPlan& planned, const PlanStep& step,
                                   double point_planned_s) {
  const DaemonConfig& config = ctx_.config;
  PointTiming timing;
  const auto motion_end = timing.motion_complete = Clock::now();
  // An ISO 9283-style test reads every pose after the full dwell, as the standard's "settled".
  const RunContext::Dwell dwell = ctx_.dwell(motion_end, plan_.purpose != PlanPurpose::kIsoTest);
  const RunContext::Measurement m = ctx_.measureHere();
  if (dwell.audited) auditDwell(planned, step, dwell, m);
  const double dwell_s = std::chrono::duration<double>(m.bar_window_start - motion_end).count();
  Sample s = shellSample(planned, m);
  s.lat_deg = step.lat_deg;
  s.lon_deg = step.lon_deg;
  // Unix time: a run resumed after a restart keeps one clock (the drift of a reference pose).
  s.time_s =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  s.approach_deg = approachDeg();
  dir_.appendSample(s, m.spread_mm);  // on disk before the robot moves again
  timing.sample_on_disk = Clock::now();
  timing.bar_window_start = m.bar_window_start;
  timing.where_end = m.where_end;
  dir_.logEvent(timing.toEvent(s.shell, s.lat_deg, s.lon_deg, config.settle_s,
                               dwell.adaptive ? "adaptive" : "fixed", dwell.ended_early));
  ctx_.reportLinkFaults(dir_);
  samples_.push_back(s);
  centring_.add(s);
  done_.insert(pointKey(s.shell, s.lat_deg, s.lon_deg));
  ctx_.publish(
      proto::toJson(proto::Sample{s.shell, s.lat_deg, s.lon_deg,
                                  std::vector<double>(m.joints_deg.data(), m.joints_deg.data() + 6),
                                  s.length_mm, m.spread_mm, static_cast<int>(m.readings), dwell_s}),
      false);
  const auto now = Clock::now();
  time_left_.pointMeasured(point_planned_s,
                           std::chrono::duration<double>(now - pace_mark_).count());
  pace_mark_ = now;
  progress();
  if (const std::string suspect = shell_watch_.point(m.deflection_mm, m.noise_mm);
      !suspect.empty()) {
    const Connection& c = planned.connection;
    throw StopRun{StopRun::kFault, "shell " + std::to_string(planned.shell) + " " +
                                       connectionName(c) + ": " + suspect + ": check that ball " +
                                       std::to_string(c.ball_index + 1) +
                                       " is tight in its socket and the bar sits in chuck " +
                                       std::to_string(c.chuck_index + 1) + ", then resume"};
  }
  return m.joints_deg;
}

void ShellRunner::auditDwell(const ShellPlan& planned, const PlanStep& step,
                             const RunContext::Dwell& dwell, const RunContext::Measurement& m) {
  const DwellAudit::Verdict v = ctx_.audit(dwell, m);
  ctx_.event(dir_, {{"event", "dwell_audit"},
                    {"shell", planned.shell},
                    {"lat_deg", step.lat_deg},
                    {"lon_deg", step.lon_deg},
                    {"adaptive_mm", dwell.audit_mean_mm},
                    {"fixed_mm", m.deflection_mm},
                    {"difference_mm", v.difference_mm},
                    {"sigma_mm", v.sigma_mm},
                    {"noise_mm", dwell.noise_mm},
                    {"measured_noise_mm", ctx_.measuredNoiseMm().value_or(0)},
                    {"passed", v.passed}});
  if (v.passed || ctx_.adaptiveTrusted()) return;
  char why[200];
  std::snprintf(why, sizeof why,
                "the adaptive dwell's reading differed from the full dwell's by %+.4f mm (%.1f "
                "sigma) again: the rest of the run dwells settle_s at every point",
                v.difference_mm, v.sigma_mm > 0 ? v.difference_mm / v.sigma_mm : 0.0);
  spdlog::warn("shell {}: {}", planned.shell, why);
  ctx_.event(dir_, {{"event", "adaptive_dwell_off"}, {"shell", planned.shell}, {"reason", why}});
}

void ShellRunner::completeSet(std::size_t shell_index, bool only_unfitted) {
  const double extension_mm = plan_.shells[shell_index].extension_mm;
  // A shell set is complete when no later shell has the same extension.
  for (std::size_t k = shell_index + 1; k < plan_.shells.size(); ++k)
    if (plan_.shells[k].extension_mm == extension_mm) return;
  // Sets are numbered by the order of their extensions' first shells.
  std::vector<double> seen;
  for (const auto& sh : plan_.shells) {
    if (std::find(seen.begin(), seen.end(), sh.extension_mm) == seen.end())
      seen.push_back(sh.extension_mm);
    if (sh.extension_mm == extension_mm) break;
  }
  const int set_index = static_cast<int>(seen.size());
  const bool check = plan_.purpose == PlanPurpose::kCheck;
  const bool iso = plan_.purpose == PlanPurpose::kIsoTest && plan_.iso;
  const std::string outcome_file = check ? "check.json"
                                   : iso ? "iso9283.json"
                                         : "result-set" + std::to_string(set_index) + ".json";
  if (only_unfitted && std::filesystem::exists(dir_.file(outcome_file))) return;
  ctx_.event(dir_, {{"event", "set_complete"},
                    {"set", set_index},
                    {"extension_mm", extension_mm},
                    {"again", only_unfitted}});
  if (check)
    fits_.launchCheck(dir_, samples_);  // a verdict on the active model, not a new fit
  else if (iso)
    fits_.launchIso(dir_, samples_, *plan_.iso);  // the test's figures, not a fit
  else
    fits_.launch(dir_, samples_, extension_mm, set_index, approachDeg());
}

double ShellRunner::approachDeg() const {
  // The plan's approach, unless the cell the re-plans use has another: then some points were
  // reached with the smaller, and the record (and the model) says that (0: none assumed).
  return std::min(plan_.cell.motion.approach_deg, cell_.motion.approach_deg);
}

}  // namespace robocal::daemon
