// A joint's twist under gravity as a parameter (docs/model-format.md, "Covariance"): the twist per
// N m of joint j turns it by its gravity torque times the twist, as its offset would, so a
// twist's column of any Jacobian is the joint's offset column times its torque (deg to rad). The
// torque is the one at the rigid pose, as Kinematics twists the readings. The design
// (planner/design.hpp), the fit's covariance (solver/compliance_fit.hpp), the verdict's whitening
// and the predicted errors (compensation/compensate.hpp) all take the twist's columns from here.
// Math only.
#pragma once

#include <robocal/kinematics/gravity.hpp>
#include <robocal/kinematics/kinematics.hpp>

#include <array>
#include <optional>

namespace robocal {

// Each joint's gravity torque (N m) from a model's load at the rigid pose of given readings;
// zeros for a model without a load. The rigid chain is built once, for the many poses of a fit,
// a check or a design.
class RigidGravityTorque {
 public:
  explicit RigidGravityTorque(const Model& model);
  std::array<double, kJointCount> operator()(const JointsDeg& readings) const;

 private:
  Kinematics rigid_;
  std::optional<GravityLoad> load_;
};

// The twists' columns (per deg/(N m)) of a Jacobian on the 54 parameters (any number of rows,
// ParamVector units) at a pose whose torques are `torque_nm`: one column per joint.
template <typename Derived>
Eigen::Matrix<double, Derived::RowsAtCompileTime, kJointCount> twistColumns(
    const Eigen::MatrixBase<Derived>& full, const std::array<double, kJointCount>& torque_nm) {
  Eigen::Matrix<double, Derived::RowsAtCompileTime, kJointCount> out(full.rows(), kJointCount);
  for (int j = 0; j < kJointCount; ++j)
    out.col(j) = full.col(jointParamIndex(j)) * (torque_nm[j] * kRadPerDeg);
  return out;
}

// Whether a covariance (Model::covariance) holds the twists' rows after the 54.
inline bool hasTwistRows(const Eigen::MatrixXd& covariance) {
  return covariance.rows() == twistCovarianceIndex(kJointCount);
}

// The 54's covariance with the twist taken as known: for a covariance with the twists' rows, the
// 54's block conditioned on the twists it holds (C_pp - C_pc C_cc^-1 C_cp, the covariance of the
// fit at a fixed twist); the 54's block of any other. A model that keeps its start's twist (one
// not told from noise) is judged by it where a change since the calibration is the question.
Eigen::MatrixXd covarianceAtKnownTwist(const Eigen::MatrixXd& covariance);
// A covariance with the twists' rows without those the fit did not look for: rows independent of
// the 54 (a prior's size for a joint too little loaded at the shells, solver/compliance_fit.hpp),
// zeroed. What the calibration itself measured; any other covariance as it is.
Eigen::MatrixXd withoutUnfittedTwists(const Eigen::MatrixXd& covariance);

}  // namespace robocal
