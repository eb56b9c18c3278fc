// Forward kinematics, ball positions, the ball-bar length model and their analytic Jacobians
// with respect to the 54 parameters. No I/O.
#pragma once

#include <robocal/kinematics/model.hpp>

#include <array>

namespace robocal {

using ParamRow = Eigen::Matrix<double, 1, kParamCount>;
using PositionJacobian = Eigen::Matrix<double, 3, kParamCount>;  // d ball / d params
using JointJacobian = Eigen::Matrix<double, 6, kJointCount>;     // d (v, w) / d readings (rad)

// A model's kinematics with the per-link constants precomputed, so that evaluating many poses
// with the same parameters is cheap. Immutable and thread-safe after construction.
class Kinematics {
 public:
  explicit Kinematics(const ParamVector& params);
  explicit Kinematics(const Model& model) : Kinematics(toParams(model)) {}

  const ParamVector& params() const { return params_; }

  // Pose of the last link's frame (after L6) in the global frame.
  Eigen::Isometry3d toolPose(const JointsDeg& readings) const;
  // Frames after each of the 13 factors L0, J1, L1, ..., J6, L6, in the global frame.
  std::array<Eigen::Isometry3d, 2 * kJointCount + 1> chainFrames(const JointsDeg& readings) const;

  Eigen::Vector3d ballPosition(const JointsDeg& readings, const Eigen::Vector3d& ball_mm) const;
  // Ball position and its analytic Jacobian with respect to all 54 parameters
  // (columns in ParamVector units: per mm, per radian, per unit gain).
  Eigen::Vector3d ballPositionJacobian(const JointsDeg& readings, const Eigen::Vector3d& ball_mm,
                                       PositionJacobian& jacobian) const;

  // Distance between the ball's centre and the chuck's centre (mm).
  double barLength(const JointsDeg& readings, const Eigen::Vector3d& ball_mm,
                   const Eigen::Vector3d& chuck_mm) const;
  // The same length and its gradient with respect to all 54 parameters.
  double barLengthGradient(const JointsDeg& readings, const Eigen::Vector3d& ball_mm,
                           const Eigen::Vector3d& chuck_mm, ParamRow& gradient) const;

  // Geometric Jacobian of the tool frame: rows (linear velocity in mm, angular velocity) in the
  // global frame, of the point `tool_point_mm` (in the last link frame), per radian of reading.
  JointJacobian jointJacobian(const JointsDeg& readings,
                              const Eigen::Vector3d& tool_point_mm = Eigen::Vector3d::Zero()) const;

 private:
  struct LinkConstants {
    Eigen::Isometry3d full;      // Trans * Rz * Ry * Rx
    Eigen::Isometry3d after_rz;  // Trans * Rz
    Eigen::Isometry3d after_ry;  // Trans * Rz * Ry
  };
  ParamVector params_;
  std::array<LinkConstants, kLinkCount> links_;
};

}  // namespace robocal
