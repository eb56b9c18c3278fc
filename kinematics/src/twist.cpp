#include <robocal/kinematics/gravity.hpp>
#include <robocal/kinematics/twist.hpp>

namespace robocal {

std::array<double, kJointCount> rigidGravityTorqueNm(const Model& model,
                                                     const JointsDeg& readings) {
  if (!model.compliance) return {};
  return gravityTorqueNm(Kinematics(toParams(model)).chainFrames(readings), model.compliance->load);
}

}  // namespace robocal
