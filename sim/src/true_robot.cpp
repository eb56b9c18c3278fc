#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/units.hpp>
#include <robocal/sim/true_robot.hpp>

#include <cmath>

namespace robocal {
Realism Realism::typical(const GravityLoad& arm_load) {
  Realism r;
  r.backlash_deg = {0.01, 0.01, 0.01, 0.01, 0.01, 0.01};
  bool has_mass = arm_load.payload_kg > 0;
  for (double m : arm_load.link_mass_kg) has_mass = has_mass || m > 0;
  if (has_mass) {
    r.compliance.load = arm_load;
    // About 0.03 deg at the largest gravity torque of a PUMA's joints 2 and 3 with the fixture
    // (robocal simulate prints the largest twist), the wrist's much stiffer in proportion to its
    // torques.
    r.compliance.deg_per_nm = {0.0, 7.0e-4, 1.5e-3, 2.0e-3, 2.0e-3, 2.0e-3};
  }
  r.warmup_k = 3.0;
  r.lvdt_gain_error = 1e-4;
  r.lvdt_nonlinearity_mm = 0.0075;
  return r;
}

bool Realism::isIdeal() const {
  for (int j = 0; j < kJointCount; ++j)
    if (backlash_deg[j] != 0) return false;
  return !compliance.twists() && warmup_k == 0 && lvdt_gain_error == 0 &&
         lvdt_nonlinearity_mm == 0 && bar_length_error == 0;
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
  GravityLoad load = realism.compliance.load;
  load.payload_kg = payload_kg;
  load.payload_com_mm = payload_com_mm;
  return robocal::gravityTorqueNm(Kinematics(toParams(model)).chainFrames(readings_deg), load);
}

JointsDeg TrueRobot::effectiveReadings(const JointsDeg& readings_deg,
                                       const Approach& approach) const {
  return effectiveReadings(readings_deg, approach, realism.compliance.load.payload_kg,
                           realism.compliance.load.payload_com_mm);
}

JointsDeg TrueRobot::effectiveReadings(const JointsDeg& readings_deg, const Approach& approach,
                                       double payload_kg,
                                       const Eigen::Vector3d& payload_com_mm) const {
  std::array<double, kJointCount> torque{};
  if (realism.compliance.twists())
    torque = gravityTorqueNm(readings_deg, payload_kg, payload_com_mm);
  JointsDeg q = readings_deg;
  for (int j = 0; j < kJointCount; ++j) {
    const double angle_deg =
        0.5 * realism.backlash_deg[j] * approach[j] + realism.compliance.deg_per_nm[j] * torque[j];
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
