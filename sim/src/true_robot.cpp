#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/units.hpp>
#include <robocal/sim/true_robot.hpp>

#include <cmath>

namespace robocal {
namespace {

constexpr double kStandardGravity = 9.80665;  // m/s^2

}  // namespace

Realism Realism::puma560Typical() {
  Realism r;
  r.backlash_deg = {0.01, 0.01, 0.01, 0.01, 0.01, 0.01};
  // Armstrong, Khatib and Burdick (ICRA 1986) as tabulated in Corke's mdl_puma560: link masses
  // (link 1 turns about the vertical: no gravity torque) and centres of mass (m there, mm here).
  r.link_mass_kg = {0.0, 17.4, 4.8, 0.82, 0.34, 0.09};
  r.link_com_mm = {Eigen::Vector3d(0, 0, 0),          Eigen::Vector3d(-363.8, 6, 227.5),
                   Eigen::Vector3d(-20.3, -14.1, 70), Eigen::Vector3d(0, 19, 0),
                   Eigen::Vector3d(0, 0, 0),          Eigen::Vector3d(0, 0, 32)};
  r.payload_kg = 1.0;  // the ball fixture
  r.payload_com_mm = Eigen::Vector3d(0, 0, 60);
  // About 0.03 deg at the largest gravity torque of joints 2 and 3 with the fixture (robocal
  // simulate prints the largest twist), the wrist's much stiffer in proportion to its torques.
  r.compliance_deg_per_nm = {0.0, 7.0e-4, 1.5e-3, 2.0e-3, 2.0e-3, 2.0e-3};
  r.warmup_k = 3.0;
  r.lvdt_gain_error = 1e-4;
  r.lvdt_nonlinearity_mm = 0.0075;
  return r;
}

bool Realism::isIdeal() const {
  for (int j = 0; j < kJointCount; ++j)
    if (backlash_deg[j] != 0 || compliance_deg_per_nm[j] != 0) return false;
  return warmup_k == 0 && lvdt_gain_error == 0 && lvdt_nonlinearity_mm == 0 &&
         bar_length_error == 0;
}

Approach approachOf(const JointsDeg& from_deg, const JointsDeg& to_deg, const Approach& previous) {
  Approach a = previous;
  for (int j = 0; j < kJointCount; ++j) {
    const double step = to_deg[j] - from_deg[j];
    if (std::abs(step) > 1e-9) a[j] = step > 0 ? 1 : -1;
  }
  return a;
}

std::array<double, kJointCount> TrueRobot::gravityTorqueNm(
    const JointsDeg& readings_deg, double payload_kg, const Eigen::Vector3d& payload_com_mm) const {
  const auto frames = Kinematics(model).chainFrames(readings_deg);
  // Each body's weight (N) and where it acts (m), in the world frame; the payload last.
  std::array<Eigen::Vector3d, kJointCount + 1> at_m, weight_n;
  for (int k = 0; k < kJointCount; ++k) {
    at_m[k] = frames[2 * (k + 1)] * realism.link_com_mm[k] * 1e-3;
    weight_n[k] = realism.link_mass_kg[k] * kStandardGravity * realism.gravity_direction;
  }
  at_m[kJointCount] = frames.back() * payload_com_mm * 1e-3;
  weight_n[kJointCount] = payload_kg * kStandardGravity * realism.gravity_direction;
  std::array<double, kJointCount> torque{};
  for (int j = 0; j < kJointCount; ++j) {
    // Joint j turns the frame after L_{j-1} about its z axis; it carries bodies j..6 and the
    // payload.
    const Eigen::Isometry3d& joint = frames[2 * j + 1];
    const Eigen::Vector3d origin_m = joint.translation() * 1e-3, axis = joint.linear().col(2);
    for (int k = j; k <= kJointCount; ++k)
      torque[j] += (at_m[k] - origin_m).cross(weight_n[k]).dot(axis);
  }
  return torque;
}

JointsDeg TrueRobot::effectiveReadings(const JointsDeg& readings_deg,
                                       const Approach& approach) const {
  return effectiveReadings(readings_deg, approach, realism.payload_kg, realism.payload_com_mm);
}

JointsDeg TrueRobot::effectiveReadings(const JointsDeg& readings_deg, const Approach& approach,
                                       double payload_kg,
                                       const Eigen::Vector3d& payload_com_mm) const {
  bool compliant = false;
  for (double c : realism.compliance_deg_per_nm) compliant = compliant || c != 0;
  std::array<double, kJointCount> torque{};
  if (compliant) torque = gravityTorqueNm(readings_deg, payload_kg, payload_com_mm);
  JointsDeg q = readings_deg;
  for (int j = 0; j < kJointCount; ++j) {
    const double angle_deg =
        0.5 * realism.backlash_deg[j] * approach[j] + realism.compliance_deg_per_nm[j] * torque[j];
    q[j] += angle_deg / model.joints[j].gain;
  }
  return q;
}

Model TrueRobot::modelAt(double minutes) const {
  if (realism.warmup_k == 0) return model;
  const double tau = std::max(realism.warmup_time_constant_min, 1e-9);
  const double growth =
      realism.thermal_expansion_per_k * realism.warmup_k * (1 - std::exp(-minutes / tau));
  Model m = model;
  for (int k = 1; k < kLinkCount; ++k) {  // L0 places the arm on the table: not the arm's steel
    m.links[k].x_mm *= 1 + growth;
    m.links[k].y_mm *= 1 + growth;
    m.links[k].z_mm *= 1 + growth;
  }
  return m;
}

double TrueRobot::measuredLength(double true_distance_mm, double stated_mm) const {
  const double true_bar_mm = stated_mm * (1 + realism.bar_length_error);
  const double d = true_distance_mm - true_bar_mm;
  const double reading = d * (1 + realism.lvdt_gain_error) +
                         realism.lvdt_nonlinearity_mm *
                             std::sin(M_PI * d / std::max(realism.lvdt_half_travel_mm, 1e-9));
  return stated_mm + reading;
}

}  // namespace robocal
