// The identification problem: residual r_i = measured length - model length of sample i, and its
// Jacobian d r / d p (54 columns, ParamVector units). Rows are independent per sample.
#pragma once

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/sample.hpp>

#include <Eigen/Core>
#include <array>
#include <optional>
#include <vector>

namespace robocal {

// The bar-length model at one parameter point, for evaluating samples one at a time: the same
// values as Kinematics::barLength and barLengthGradient (to rounding), computed for this one use.
// The per-link constants are made once; per sample, each joint rotation turns two columns of the
// frame by (cos, sin) instead of a general 4x4 product, and the gradient is taken as
// u . (axis x lever) = axis . (lever x u) from the frames of the forward pass, without the
// 3 x 54 position Jacobian. evaluateProblem uses it; the benchmark gives it to Ceres too. A model
// with gravity compliance (Model::compliance) is evaluated at the twisted readings, as Kinematics
// does; its gradient leaves out the twist's own change with the parameters (second order).
class BarLengthModel {
 public:
  BarLengthModel(const Model& fixtures, const ParamVector& params);
  // Distance between the sample's ball and chuck centres (mm) at the sample's joint readings.
  double length(const Sample& sample) const;
  // The same length, and its gradient with respect to the 54 parameters in `gradient`.
  double lengthGradient(const Sample& sample, double* gradient) const;

 private:
  template <bool kGradient>
  double evaluate(const Sample& sample, double* gradient) const;
  struct Link {
    Eigen::Matrix3d rotation;  // Rz * Ry * Rx
    Eigen::Vector3d translation;
    Eigen::Vector3d ry_axis;  // axis of the link's ry in its frame before the rotation: Rz e_y
    Eigen::Vector3d rx_axis;  // axis of its rx: Rz Ry e_x
  };
  std::array<Link, kLinkCount> links_;
  std::array<double, kJointCount> offset_rad_{}, gain_{};
  std::array<Eigen::Vector3d, kBallCount> balls_mm_;
  std::array<Eigen::Vector3d, kChuckCount> chucks_mm_;
  // The model with its compliance, when it twists: each sample's readings are twisted by it
  // (Kinematics::twistedReadings) before the rigid chain is evaluated.
  std::optional<Kinematics> loaded_;
};

// Fills residuals (n) and, when jacobian is not null, the n x 54 Jacobian. The balls and chucks
// come from `fixtures`; the 54 parameters from `params`.
void evaluateProblem(const Model& fixtures, const ParamVector& params,
                     const std::vector<Sample>& samples, Eigen::VectorXd& residuals,
                     Eigen::MatrixXd* jacobian);

}  // namespace robocal
