// The identification problem: residual r_i = measured length - model length of sample i, and its
// Jacobian d r / d p (54 columns, ParamVector units). Rows are independent per sample.
#pragma once

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/sample.hpp>

#include <Eigen/Core>
#include <vector>

namespace robocal {

// Fills residuals (n) and, when jacobian is not null, the n x 54 Jacobian. The balls and chucks
// come from `fixtures`; the 54 parameters from `params`.
void evaluateProblem(const Model& fixtures, const ParamVector& params,
                     const std::vector<Sample>& samples, Eigen::VectorXd& residuals,
                     Eigen::MatrixXd* jacobian);

}  // namespace robocal
