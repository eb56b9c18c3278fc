// Gravity compliance: a joint twists by its compliance times the gravity torque it carries at the
// pose, from the weights of the bodies it moves and of the payload at the tool. A real arm's
// joints 2 and 3 twist by a few hundredths of a degree (docs/realism.md); over the few shells of a
// calibration the joint offsets and gains absorb that, and it comes back over the arm's whole
// range (docs/accuracy.md). The simulated true robot twists its joints with it, and a model that
// carries it (Model::compliance, GravityLoad and JointCompliance in model.hpp) is evaluated at the
// twisted angles by Kinematics. Math only.
#pragma once

#include <robocal/kinematics/model.hpp>

#include <array>

namespace robocal {

using ChainFrames = std::array<Eigen::Isometry3d, 2 * kJointCount + 1>;

// The gravity torque each joint carries (N m) in the chain's frames (Kinematics::chainFrames).
std::array<double, kJointCount> gravityTorqueNm(const ChainFrames& frames, const GravityLoad& load);

}  // namespace robocal
