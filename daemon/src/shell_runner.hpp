// One session of a run on the robot: the shells of the plan not yet measured, one after another.
// For each: the bar off the robot, the connect pose, the operator's connection (with nudges),
// the reading near zero, the connection check; then the steps, watched, with a sample recorded at
// each data point, the bar kept centred (Centring) and the rest of the shell re-planned from
// where the robot is; a completed shell set goes to the fit. The run ends with the bar detached.
// A stop (pause, fault, abort) is thrown as StopRun.
#pragma once

#include "centring.hpp"
#include "fit_job.hpp"
#include "run_context.hpp"

#include <robocal/daemon/shell_watch.hpp>
#include <robocal/daemon/time_left.hpp>

#include <set>
#include <tuple>
#include <vector>

namespace robocal::daemon {

class ShellRunner {
 public:
  ShellRunner(RunContext& ctx, FitJob& fits, RunDir& dir, const Plan& plan);
  void run();

 private:
  bool isDone(int shell, const PlanStep& step) const;
  int pointsLeft(const ShellPlan& shell) const;
  // Robot time left: the plan's time for the points not yet measured, at the pace measured.
  double timeLeftSeconds() const;
  // The robot time a data point of this shell takes by the plan's duration model, with this
  // daemon's dwell and bar window in place of the cell's planned dwell.
  double plannedPointSeconds(const ShellPlan& shell) const;
  void progress();

  // Asks the operator to detach the bar, then proves it before the robot moves on: the ball
  // moves a fraction of a millimetre along the line to the chuck it was on, and the bar must
  // not follow (a detach confirmed with the bar still on would otherwise meet a whole move at
  // full speed). StopRun when it follows, the bar recorded as maybe attached.
  void detach(int shell_number, const std::string& message);
  // The operator's nudge of `mm` along the bar's line at a connect prompt, in creeping steps
  // watched for a bar that follows; where the robot stands after it.
  JointsDeg nudge(const ShellPlan& shell, JointsDeg q, double mm);
  // Up to the bar attached, read near zero and checked; the joints where the robot stands.
  JointsDeg connect(const ShellPlan& shell);
  // After a connect: the ball moves a small step along the expected bar line and back past the
  // start, and the bar must follow (connection_check.hpp). The ball ends where it started.
  void verifyConnection(const ShellPlan& shell, JointsDeg& q);
  // The shell's steps from `q`; `already` of its points were measured in an earlier session.
  void measure(const ShellPlan& planned, int already, JointsDeg q);
  // Dwells, measures and records a data point (on disk before the robot moves again); the actual
  // joints. StopRun when the shell's connection looks bad (ShellWatch).
  JointsDeg recordPoint(const ShellPlan& planned, const PlanStep& step, double point_planned_s);
  // How far every joint rose into each data point (deg), as the samples record it.
  double approachDeg() const;
  // An audited dwell's two readings compared (docs/settling.md), as a "dwell_audit" event; a
  // second failed audit turns the adaptive dwell off for the run.
  void auditDwell(const ShellPlan& planned, const PlanStep& step, const RunContext::Dwell& dwell,
                  const RunContext::Measurement& m);
  // Fits the shell set that `shell` completes, if it completes one; `only_unfitted`: only when
  // the set has no result in the run folder yet (a set measured before a kill cut its fit short).
  void completeSet(std::size_t shell_index, bool only_unfitted = false);

  // The corrective move's target (centring.hpp), or StopRun.
  JointsDeg corrected(const ShellPlan& shell, const JointsDeg& q, double deflection_mm) const;
  // Re-plans `shell`'s steps from `from` on, starting at `at`, with the latest model; a point that
  // is no longer safe to reach is dropped, and said so.
  void replanFrom(ShellPlan& shell, std::size_t from, const JointsDeg& at, const std::string& why);
  Sample shellSample(const ShellPlan& shell, const RunContext::Measurement& m) const;

  RunContext& ctx_;
  FitJob& fits_;
  RunDir& dir_;
  const Plan& plan_;
  // The cell the re-plans use, moving through vias (and blending) as the plan does: its steps
  // were marked with the plan's, the re-planned ones are marked with the same.
  const CellConfig cell_;
  std::vector<Sample> samples_;  // every data point of the run
  // (shell, lat, lon) of every sample: a point's revisit (PlanStep::visit 1) is done when its
  // place was measured twice.
  std::multiset<std::tuple<int, double, double>> done_;
  int total_points_ = 0;
  TimeLeft time_left_;
  ShellWatch shell_watch_;                           // a connection going bad mid-shell
  int replans_ = 0;                                  // numbered on from the run's earlier sessions
  std::chrono::steady_clock::time_point pace_mark_;  // the end of the last point (or prompt)
  Centring centring_;
};

}  // namespace robocal::daemon
