// The adaptive dwell's decision, without I/O: fed the bar readings after a move as (seconds
// since the move ended, value), it says when they are steady, i.e. when over the last
// `window_s` both the linear trend across the window and the spread about that trend are at the
// reader's noise level. The daemon's dwell ends at the first steady window or at settle_s,
// whichever comes first (docs/settling.md). Deterministic: the same readings give the same answer.
#pragma once

#include <cstddef>
#include <deque>

namespace robocal::daemon {

struct SteadyCriteria {
  double noise_mm = 0;           // the reader's noise, 1 sigma (must be > 0)
  double window_s = 0.5;         // the sliding window judged
  std::size_t min_readings = 8;  // fewer in the window: not steady (too little to judge)
  double trend_factor = 1.0;     // |slope| x window_s <= trend_factor x noise_mm
  double spread_factor = 1.25;   // standard deviation about the trend <= spread_factor x noise
};

class SteadyWindow {
 public:
  explicit SteadyWindow(const SteadyCriteria& criteria) : c_(criteria) {}

  // A reading `t_s` seconds after the move ended (non-decreasing); returns steady().
  bool add(double t_s, double value_mm);
  // The window is full (it spans at least 90 % of window_s with min_readings readings) and its
  // trend and spread are within the criteria.
  bool steady() const { return steady_; }
  // The last judged window's figures (0 before a full one).
  double trendMm() const { return trend_mm_; }    // fitted change across window_s
  double spreadMm() const { return spread_mm_; }  // standard deviation about the fitted line
  std::size_t readings() const { return points_.size(); }

 private:
  struct Point {
    double t_s, value_mm;
  };
  SteadyCriteria c_;
  std::deque<Point> points_;
  bool steady_ = false;
  double trend_mm_ = 0, spread_mm_ = 0;
};

}  // namespace robocal::daemon
