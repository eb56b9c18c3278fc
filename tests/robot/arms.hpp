// Arms for the robot module's tests: the nominal PUMA 560, a calibrated-like PUMA (links and
// joints moved like a calibration finds them, with small link rotations that no DH table has),
// and a UR5 from Universal Robots' published DH parameters (no spherical wrist: only the numeric
// inverse kinematics serves it).
#pragma once

#include <robocal/kinematics/units.hpp>
#include <robocal/robot/arm.hpp>
#include <robocal/robot/puma560.hpp>

#include <random>
#include <string>

namespace robocal::test {

// Universal Robots, "DH parameters for calculations of kinematics and dynamics" (UR5, CB3/e):
// d1 = 89.159, a2 = -425, a3 = -392.25, d4 = 109.15, d5 = 94.65, d6 = 82.3 mm,
// alpha = (90, 0, 0, 90, -90, 0) deg. Limits +/-180 deg on every joint (the arm allows +/-360).
inline Model ur5Model() {
  const std::array<DHRow, kJointCount> dh = {{{89.159, 0, 90, 0},
                                              {0, -425.0, 0, 0},
                                              {0, -392.25, 0, 0},
                                              {109.15, 0, 90, 0},
                                              {94.65, 0, -90, 0},
                                              {82.3, 0, 0, 0}}};
  Model m = modelFromStandardDH(dh, Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity());
  m.name = "UR5 (DH)";
  return m;
}

inline Model calibratedLikePuma(unsigned seed) {
  Model m = puma560NominalModel();
  m.name = "PUMA 560 calibrated-like " + std::to_string(seed);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> mm(0.0, 0.5), deg(0.0, 0.05);
  for (LinkParams& l : m.links) {
    l.x_mm += mm(rng), l.y_mm += mm(rng), l.z_mm += mm(rng);
    l.rz_deg += deg(rng), l.ry_deg += deg(rng), l.rx_deg += deg(rng);
  }
  for (JointParams& j : m.joints) j.offset_deg += deg(rng), j.gain += 1e-4 * deg(rng);
  return m;
}

// Readings inside the limits (1 deg in), away from the singularities by the margins robocal
// compensate calls regular (CompensationOptions: 2 deg, 2 deg, 20 mm).
inline JointsDeg randomRegularJoints(const Arm& arm, std::mt19937_64& rng) {
  for (;;) {
    JointsDeg q;
    for (int j = 0; j < kJointCount; ++j) {
      const JointParams& jp = arm.model().joints[j];
      q[j] = std::uniform_real_distribution<double>(jp.min_deg + 1, jp.max_deg - 1)(rng);
    }
    const SingularityMargins m = arm.singularityMargins(q);
    if (m.wrist_deg > 2 && m.elbow_deg > 2 && m.shoulder_mm > 20) return q;
  }
}

}  // namespace robocal::test
