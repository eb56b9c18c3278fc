#include <robocal/kinematics/gravity.hpp>

namespace robocal {
namespace {

constexpr double kStandardGravity = 9.80665;  // m/s^2

}  // namespace

std::array<double, kJointCount> gravityTorqueNm(const ChainFrames& frames,
                                                const GravityLoad& load) {
  // Each body's weight (N) and where it acts (m), in the world frame; the payload last.
  std::array<Eigen::Vector3d, kJointCount + 1> at_m, weight_n;
  for (int k = 0; k < kJointCount; ++k) {
    at_m[k] = frames[2 * (k + 1)] * load.link_com_mm[k] * 1e-3;
    weight_n[k] = load.link_mass_kg[k] * kStandardGravity * load.gravity_direction;
  }
  at_m[kJointCount] = frames.back() * load.payload_com_mm * 1e-3;
  weight_n[kJointCount] = load.payload_kg * kStandardGravity * load.gravity_direction;
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

}  // namespace robocal
