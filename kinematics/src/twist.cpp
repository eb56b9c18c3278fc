#include <robocal/kinematics/twist.hpp>

#include <vector>

namespace robocal {

RigidGravityTorque::RigidGravityTorque(const Model& model) : rigid_(toParams(model)) {
  if (model.compliance) load_ = model.compliance->load;
}

std::array<double, kJointCount> RigidGravityTorque::operator()(const JointsDeg& readings) const {
  if (!load_) return {};
  return gravityTorqueNm(rigid_.chainFrames(readings), *load_);
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

Eigen::MatrixXd withoutUnfittedTwists(const Eigen::MatrixXd& covariance) {
  Eigen::MatrixXd out = covariance;
  if (!hasTwistRows(covariance)) return out;
  for (int j = 0; j < kJointCount; ++j) {
    const int t = twistCovarianceIndex(j);
    if (covariance.block(0, t, kParamCount, 1).isZero(0)) {
      out.row(t).setZero();
      out.col(t).setZero();
    }
  }
  return out;
}

}  // namespace robocal
