#include <robocal/drivers/move_test.hpp>

#include <algorithm>
#include <cmath>

namespace robocal::drivers {
namespace {

double secondsBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// One move: the command, then WHERE until still at the target; what the controller did.
struct MoveSeen {
  double command_reply_s = 0, total_s = 0;
  std::string prompt;
  bool short_of_target_after_reply = false;
  int polls = 0;
  Joints6 end{};
};

MoveSeen move(ValController& val, const Joints6& target) {
  MoveSeen seen;
  const auto t0 = Clock::now();
  val.startMove(target);
  seen.command_reply_s = secondsBetween(t0, Clock::now());
  seen.prompt = val.lastPrompt();
  const WhereReply end = val.waitForMotion(target, [&](const WhereReply& w) {
    if (++seen.polls == 1)
      seen.short_of_target_after_reply =
          maxJointDiffDeg(w.joints_deg, target) > val.dialect().config().at_target_tol_deg;
  });
  seen.total_s = secondsBetween(t0, Clock::now());
  seen.end = end.joints_deg;
  return seen;
}

std::string verdictText(const MoveTestReport& r, const ValConfig& config) {
  std::string v = "the " + config.dialect +
                  " dialect drives this controller: " + std::to_string(r.joints.size()) +
                  " joints out and back, every move watched by " + "WHERE to its target. ";
  const bool any_async =
      std::any_of(r.joints.begin(), r.joints.end(),
                  [](const JointMoveResult& j) { return j.returned_while_moving; });
  v += any_async ? "The move command returns its prompt before the motion ends"
                 : "The move command returns its prompt when the motion ends (synchronous)";
  if (!r.joints.empty() && !r.joints.front().prompt_after_move.empty())
    v += ", showing '" + r.joints.front().prompt_after_move + "'";
  v += ". ";
  if (r.ignored_lines > 0)
    v += std::to_string(r.ignored_lines) + " completion line(s) were dropped (val.ignore_regex). ";
  if (r.move_timeouts_watched > 0)
    v += "Some move commands outlived their deadline and were watched to the end: raise "
         "val.move_timeout_s or lower val.slowest_joint_speed_deg_s. ";
  return trim(v);
}

}  // namespace

MoveTestReport runMoveTest(ValController& val, const MoveTestOptions& o,
                           const std::function<void(const std::string&)>& progress) {
  MoveTestReport r;
  const auto say = [&](const std::string& s) {
    if (progress) progress(s);
  };
  int joint = 0;
  try {
    for (int i = 0; i < 3; ++i) {
      const auto t0 = Clock::now();
      r.start_deg = val.where().joints_deg;
      r.where_round_trip_s.push_back(secondsBetween(t0, Clock::now()));
    }
    val.setSpeed(o.speed_percent);
    say("SPEED " + formatFixed(o.speed_percent, 0) + " set");
    for (joint = 1; joint <= 6; ++joint) {
      const int k = joint - 1;
      JointMoveResult j;
      j.joint = joint;
      j.step_deg = r.start_deg[k] + o.step_deg <= o.max_deg[k] ? o.step_deg : -o.step_deg;
      if (r.start_deg[k] + j.step_deg < o.min_deg[k])
        throw DriverError("joint " + std::to_string(joint) + " is too close to both of its limits");
      Joints6 out = r.start_deg;
      out[k] += j.step_deg;
      const MoveSeen there = move(val, out);
      j.out_s = there.total_s;
      j.command_reply_s = there.command_reply_s;
      j.prompt_after_move = there.prompt;
      // Returned before the motion ended: a busy prompt ("*", any but the first) came back, or
      // the first WHERE found the arm short of the target.
      j.returned_while_moving =
          (!there.prompt.empty() && there.prompt != val.dialect().idlePrompt()) ||
          there.short_of_target_after_reply;
      j.error_deg = maxJointDiffDeg(there.end, out);
      const MoveSeen back = move(val, r.start_deg);
      j.back_s = back.total_s;
      j.where_polls = there.polls + back.polls;
      r.joints.push_back(j);
      say("joint " + std::to_string(joint) + ": " + formatFixed(j.step_deg, 3) + " deg and back, " +
          formatFixed(j.out_s, 2) + " s + " + formatFixed(j.back_s, 2) + " s, " +
          std::to_string(j.where_polls) + " WHEREs, prompt '" + j.prompt_after_move + "' after " +
          formatFixed(1000 * j.command_reply_s, 0) + " ms");
    }
    r.ok = true;
  } catch (const std::exception& e) {
    r.error = (joint >= 1 && joint <= 6 ? "joint " + std::to_string(joint) + ": " : "") +
              std::string(e.what());
    try {
      val.abort();
    } catch (const std::exception&) {
      // The error above is the one to report; the operator's E-stop is the last word.
    }
  }
  r.ignored_lines = val.stats().ignored_lines;
  r.move_timeouts_watched = val.stats().move_timeouts_watched;
  r.verdict = r.ok ? verdictText(r, val.dialect().config())
                   : "the move test stopped: " + r.error +
                         ". The arm was told to ABORT; check it before you go on.";
  return r;
}

}  // namespace robocal::drivers
