// A simulated true robot that is not its model: the 54-parameter model plus the effects a real arm
// and instrument carry (docs/realism.md has their sizes and sources):
//   - gear backlash: each joint's angle is off by half its backlash, in the direction the joint
//     last moved (`approach`, +1 or -1 per joint);
//   - joint compliance under gravity: each joint twists by its compliance times the gravity torque
//     it carries at that pose (link masses and centres of mass, and the payload at the tool);
//   - thermal growth: the arm's link translations grow with a warm-up that approaches
//     `warmup_k` kelvin exponentially over the run's time;
//   - the instrument: the LVDT's gain error and a smooth nonlinearity over its travel, and an
//     error in the bar's length standard (its absolute length).
// All zero is the ideal robot that is exactly its model (`Realism::ideal()`), for tests that need
// it. Math only: no I/O (the truth file is true_robot_json.hpp).
//
// Each effect moves a joint's angle or the measured length, never the model: the true robot at
// readings q is the model at effectiveReadings(q) (backlash and compliance turn the joint as a
// reading would, divided by its gain, which is 1 to 1e-3), at its thermal state.
#pragma once

#include <robocal/kinematics/gravity.hpp>
#include <robocal/kinematics/model.hpp>

#include <array>

namespace robocal {

struct Realism {
  // Backlash, full width per joint (deg): the angle is off by +/- half of it.
  std::array<double, kJointCount> backlash_deg{};
  // Gravity compliance: joint twist per N m of gravity torque (deg/(N m)), per joint, and the
  // load (link masses and centres, the payload: the ball fixture while calibrating).
  JointCompliance compliance;
  // Thermal growth of the link translations L1..L6: alpha * warmup_k * (1 - exp(-t / tau)).
  double thermal_expansion_per_k = 11.7e-6;  // steel
  double warmup_k = 0;
  double warmup_time_constant_min = 30;
  // The instrument. reading = d (1 + gain error) + nonlinearity sin(pi d / half travel), d the true
  // deflection from the bar's true length; the bar's true length is its stated length times
  // (1 + bar_length_error).
  double lvdt_gain_error = 0;
  double lvdt_nonlinearity_mm = 0;
  double lvdt_half_travel_mm = 2.0;
  double bar_length_error = 0;

  static Realism ideal() { return {}; }
  // The middle of the sizes docs/realism.md cites: backlash 0.01 deg, the arm's link masses and
  // its fixture (`arm_load`: the nominal model's compliance load; the PUMA 560's, with a 1 kg
  // fixture, gives joints 2 and 3 about 0.03 deg of twist at their largest torque) with the
  // compliances found for the PUMA, a 3 K warm-up (30 min), an LVDT with 1e-4 gain error and
  // 7.5 um of nonlinearity. An arm whose model gives no masses gets no gravity compliance.
  static Realism typical(const GravityLoad& arm_load);
  bool isIdeal() const;
};

// The direction each joint last moved in: +1 or -1.
using Approach = std::array<int, kJointCount>;
inline constexpr Approach kPositiveApproach = {1, 1, 1, 1, 1, 1};
// Each joint's direction from `from` to `to`; a joint that does not move keeps `previous`'s.
Approach approachOf(const JointsDeg& from_deg, const JointsDeg& to_deg, const Approach& previous);

struct TrueRobot {
  Model model;
  Realism realism;

  // The gravity torque each joint carries at these readings (N m), with the given payload.
  std::array<double, kJointCount> gravityTorqueNm(const JointsDeg& readings_deg, double payload_kg,
                                                  const Eigen::Vector3d& payload_com_mm) const;
  // The readings the model must be given to put the arm where the true robot is at `readings`
  // reached with `approach`: backlash and the calibration payload's gravity compliance.
  JointsDeg effectiveReadings(const JointsDeg& readings_deg, const Approach& approach) const;
  // The same with another payload (the work tool after calibration).
  JointsDeg effectiveReadings(const JointsDeg& readings_deg, const Approach& approach,
                              double payload_kg, const Eigen::Vector3d& payload_com_mm) const;
  // The model at `minutes` into the run (thermal growth); the model itself when there is none.
  Model modelAt(double minutes) const;
  // The ball-bar's reading as a length (mm), for a bar whose stated length is `stated_mm` whose
  // ball and chuck are `true_distance_mm` apart.
  double measuredLength(double true_distance_mm, double stated_mm) const;
};

}  // namespace robocal
