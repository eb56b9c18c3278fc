// Inverse kinematics of any six-revolute arm, numerically: damped least squares from several
// seeds (Arm::solveFromSeeds). Configurations and margins are Arm's geometric ones. No I/O.
#pragma once

#include <robocal/robot/arm.hpp>

namespace robocal {

class NumericIk final : public Arm {
 public:
  explicit NumericIk(const Model& model) : Arm(model) {}

  const char* ikName() const override { return "numeric"; }
  IkSolution solve(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                   const JointsDeg* near = nullptr) const override {
    return solveFromSeeds(tool_pose, config, near);
  }
  // One descent from `seed`; from the seeds when it does not reach the target in `config`.
  IkSolution refine(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                    const JointsDeg& seed) const override;
};

}  // namespace robocal
