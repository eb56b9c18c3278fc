#include <robocal/robot/numeric_ik.hpp>

namespace robocal {

IkSolution NumericIk::refine(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                             const JointsDeg& seed) const {
  if (tool_pose.matrix().allFinite() && seed.allFinite()) {
    const Descent d = descend(tool_pose, &config, seed);
    if (found(d, config)) {
      IkSolution s;
      s.config = config;
      s.joints_deg = d.q;
      measureError(s, tool_pose);
      judgeConverged(s, tool_pose, &seed);
      return s;
    }
  }
  return solveFromSeeds(tool_pose, config, &seed);
}

}  // namespace robocal
