#include <robocal/kinematics/gravity.hpp>
#include <robocal/kinematics/twist.hpp>

#include <vector>

namespace robocal {

std::array<double, kJointCount> rigidGravityTorqueNm(const Model& model,
                                                     const JointsDeg& readings) {
  if (!model.compliance) return {};
  return gravityTorqueNm(Kinematics(toParams(model)).chainFrames(readings), model.compliance->load);
}

Eigen::MatrixXd covarianceAtKnownTwist(const Eigen::MatrixXd& covariance) {
  const Eigen::MatrixXd params = covariance.topLeftCorner(kParamCount, kParamCount);
  if (!hasTwistRows(covariance)) return params;
  std::vector<Eigen::Index> twists;  // those the covariance holds (the loaded joints')
  for (int j = 0; j < kJointCount; ++j)
    if (covariance(twistCovarianceIndex(j), twistCovarianceIndex(j)) > 0)
      twists.push_back(twistCovarianceIndex(j));
  const Eigen::Index k = static_cast<Eigen::Index>(twists.size());
  Eigen::MatrixXd cross(kParamCount, k), twist(k, k);
  for (Eigen::Index a = 0; a < k; ++a) {
    cross.col(a) = covariance.block(0, twists[a], kParamCount, 1);
    for (Eigen::Index b = 0; b < k; ++b) twist(a, b) = covariance(twists[a], twists[b]);
  }
  return params - cross * twist.ldlt().solve(cross.transpose());
}

}  // namespace robocal
