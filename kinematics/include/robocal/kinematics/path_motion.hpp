// Joint motion through waypoints, as robocal-cellsim plays a controller and the planner checks a
// path the arm blends: from where the arm is, each segment joint-interpolated at the joints'
// common speed (its largest joint change / speed), consecutive segments run without a stop. A
// program's path (motion through vias) is blended: the piecewise-linear path is averaged over a
// window of blend_deg of travel (the largest joint's), as a controller's acceleration between
// segments does, so the arm cuts each corner on the inside of its via (by about the corner's
// change of joint direction x blend_deg / 8) and comes to rest blend_deg of travel after the last
// segment's end. Given in degrees of travel, not seconds, the cut is the same at every speed: the
// planner checks the path cellsim will run. A single DO MOVE has no corner (blend_deg 0). An
// assumption about real controllers, not a measurement (docs/cell-time.md). Math only.
#pragma once

#include <robocal/kinematics/model.hpp>

#include <algorithm>
#include <vector>

namespace robocal {

class PathMotion {
 public:
  // speed_deg_s > 0 (the clock's unit: 1 makes time the travel in degrees); blend_deg >= 0.
  PathMotion(const JointsDeg& from, const std::vector<JointsDeg>& waypoints, double speed_deg_s,
             double blend_deg)
      : blend_s_(blend_deg / speed_deg_s) {
    points_.push_back(from);
    ends_s_.push_back(0);
    for (const JointsDeg& to : waypoints) {
      ends_s_.push_back(ends_s_.back() + (to - points_.back()).cwiseAbs().maxCoeff() / speed_deg_s);
      points_.push_back(to);
    }
  }

  // When the arm is at rest at the last waypoint.
  double durationS() const { return ends_s_.back() + blend_s_; }
  // When the unblended path reaches waypoint k (0: the start).
  double reachedS(std::size_t k) const { return ends_s_[k]; }
  const JointsDeg& target() const { return points_.back(); }
  // The waypoint before the last (where the final approach comes from).
  const JointsDeg& lastFrom() const { return points_[points_.size() - 2]; }

  JointsDeg at(double t_s) const {
    if (blend_s_ <= 0) return linear(t_s);
    // The mean of the linear path over [t - blend, t], by the midpoint rule.
    constexpr int kSamples = 16;
    JointsDeg sum = JointsDeg::Zero();
    for (int k = 0; k < kSamples; ++k) sum += linear(t_s - blend_s_ * (k + 0.5) / kSamples);
    return sum / kSamples;
  }

 private:
  JointsDeg linear(double t_s) const {
    if (t_s <= 0) return points_.front();
    const auto it = std::lower_bound(ends_s_.begin(), ends_s_.end(), t_s);
    if (it == ends_s_.end()) return points_.back();
    const auto k = static_cast<std::size_t>(it - ends_s_.begin());  // segment k-1 -> k
    const double span = ends_s_[k] - ends_s_[k - 1];
    const double s = span > 0 ? (t_s - ends_s_[k - 1]) / span : 1.0;
    return points_[k - 1] + (points_[k] - points_[k - 1]) * s;
  }

  std::vector<JointsDeg> points_;  // from, then the waypoints
  std::vector<double> ends_s_;     // when the linear path reaches each
  double blend_s_;
};

}  // namespace robocal
