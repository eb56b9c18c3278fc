// The time left in a run: the plan's duration model for what remains (moves at the planned joint
// speed plus the planned dwell at each point), scaled by the pace measured so far in this session
// (actual time per point over planned time per point). The operator's time at prompts counts in
// neither: the pace is measured only while the robot measures. Pure arithmetic, no clock.
#pragma once

#include <algorithm>

namespace robocal::daemon {

class TimeLeft {
 public:
  // A point that the plan gives `planned_s` took `actual_s` (move, dwell, window, recentres).
  void pointMeasured(double planned_s, double actual_s) {
    planned_s_ += planned_s;
    actual_s_ += actual_s;
    ++points_;
  }
  // Actual over planned time; 1 until a few points have been measured.
  double pace() const {
    if (points_ < kPointsBeforePace || planned_s_ <= 0) return 1.0;
    return std::clamp(actual_s_ / planned_s_, 0.01, 100.0);
  }
  double seconds(double remaining_planned_s) const {
    return std::max(0.0, remaining_planned_s) * pace();
  }

 private:
  static constexpr int kPointsBeforePace = 3;
  double planned_s_ = 0, actual_s_ = 0;
  int points_ = 0;
};

}  // namespace robocal::daemon
