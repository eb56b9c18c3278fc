// Forward kinematics, ball positions, the ball-bar length model and their analytic Jacobians
// with respect to the 54 parameters. No I/O.
#pragma once

#include <robocal/kinematics/gravity.hpp>
#include <robocal/kinematics/model.hpp>

#include <array>
#include <optional>

namespace robocal {

using ParamRow = Eigen::Matrix<double, 1, kParamCount>;
using PositionJacobian = Eigen::Matrix<double, 3, kParamCount>;  // d ball / d params
using JointJacobian = Eigen::Matrix<double, 6, kJointCount>;     // d (v, w) / d readings (rad)

// A model's kinematics with the per-link constants precomputed, so that evaluating many poses
// with the same parameters is cheap. Immutable and thread-safe after construction.
//
// Made from a Model that carries gravity compliance, every function below takes the readings to
// the joint angles the loaded arm has: each joint twisted by its compliance times the gravity
// torque at the pose (twistedReadings). The parameter and joint Jacobians leave out the torque's
// own change with the parameters and the readings (a few hundredths of a degree of twist: second
// order). Made from a ParamVector, the arm is rigid.
class Kinematics {
 public:
  explicit Kinematics(const ParamVector& params);
  explicit Kinematics(const Model& model);

  const ParamVector& params() const { return params_; }
  // The readings a rigid arm with these parameters needs to put its joints where the loaded arm's
  // are at `readings` (deg): readings + twist / gain. The readings themselves for a rigid arm.
  JointsDeg twistedReadings(const JointsDeg& readings) const;

  // Pose of the last link's frame (after L6) in the global frame.
  Eigen::Isometry3d toolPose(const JointsDeg& readings) const;
  // Frames after each of the 13 factors L0, J1, L1, ..., J6, L6, in the global frame.
  ChainFrames chainFrames(const JointsDeg& readings) const;

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
  ChainFrames rigidChainFrames(const JointsDeg& readings) const;
  ParamVector params_;
  std::array<LinkConstants, kLinkCount> links_;
  std::optional<JointCompliance> compliance_;  // only when it twists
};

}  // namespace robocal
