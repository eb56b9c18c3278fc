#include <robocal/kinematics/kinematics.hpp>

#include <robocal/kinematics/units.hpp>

namespace robocal {
namespace {

Eigen::Isometry3d rotZ(double angle_rad) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(angle_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return t;
}

// Joint angle (rad) of joint j for a reading in degrees.
double theta(const ParamVector& p, int j, double reading_deg) {
  const int i = jointParamIndex(j);
  return jointAngleRad(p[i], p[i + 1], reading_deg);
}

}  // namespace

Kinematics::Kinematics(const ParamVector& params) : params_(params) {
  for (int k = 0; k < kLinkCount; ++k) {
    const int i = linkParamIndex(k);
    LinkConstants& c = links_[k];
    Eigen::Isometry3d trans = Eigen::Isometry3d::Identity();
    trans.translation() = params.segment<3>(i);
    c.after_rz = trans * Eigen::AngleAxisd(params[i + 3], Eigen::Vector3d::UnitZ());
    c.after_ry = c.after_rz * Eigen::AngleAxisd(params[i + 4], Eigen::Vector3d::UnitY());
    c.full = c.after_ry * Eigen::AngleAxisd(params[i + 5], Eigen::Vector3d::UnitX());
  }
}

Kinematics::Kinematics(const Model& model) : Kinematics(toParams(model)) {
  if (model.compliance && model.compliance->twists()) compliance_ = model.compliance;
}

JointsDeg Kinematics::twistedReadings(const JointsDeg& readings) const {
  if (!compliance_) return readings;
  const std::array<double, kJointCount> torque_nm =
      gravityTorqueNm(rigidChainFrames(readings), compliance_->load);
  JointsDeg q = readings;
  for (int j = 0; j < kJointCount; ++j)
    q[j] += compliance_->deg_per_nm[j] * torque_nm[j] / params_[jointParamIndex(j) + 1];
  return q;
}

ChainFrames Kinematics::chainFrames(const JointsDeg& readings) const {
  return rigidChainFrames(twistedReadings(readings));
}

ChainFrames Kinematics::rigidChainFrames(const JointsDeg& readings) const {
  ChainFrames frames;
  frames[0] = links_[0].full;
  for (int j = 0; j < kJointCount; ++j) {
    frames[2 * j + 1] = frames[2 * j] * rotZ(theta(params_, j, readings[j]));
    frames[2 * j + 2] = frames[2 * j + 1] * links_[j + 1].full;
  }
  return frames;
}

Eigen::Isometry3d Kinematics::toolPose(const JointsDeg& readings) const {
  const JointsDeg q = twistedReadings(readings);
  Eigen::Isometry3d t = links_[0].full;
  for (int j = 0; j < kJointCount; ++j) t = t * rotZ(theta(params_, j, q[j])) * links_[j + 1].full;
  return t;
}

Eigen::Vector3d Kinematics::ballPosition(const JointsDeg& readings,
                                         const Eigen::Vector3d& ball_mm) const {
  return toolPose(readings) * ball_mm;
}

Eigen::Vector3d Kinematics::ballPositionJacobian(const JointsDeg& readings,
                                                 const Eigen::Vector3d& ball_mm,
                                                 PositionJacobian& jac) const {
  const auto frames = chainFrames(readings);
  Eigen::Vector3d ball = frames.back() * ball_mm;
  // A parameter that rotates the chain about an axis through point o moves the ball by
  // axis x (ball - o); a translation moves it along the translated axis.
  for (int k = 0; k < kLinkCount; ++k) {
    const Eigen::Isometry3d before = k == 0 ? Eigen::Isometry3d::Identity() : frames[2 * k - 1];
    const LinkConstants& c = links_[k];
    const int i = linkParamIndex(k);
    jac.block<3, 3>(0, i) = before.linear();
    const Eigen::Vector3d origin = before * c.after_rz.translation();
    const Eigen::Vector3d lever = ball - origin;
    jac.col(i + 3) = before.linear().col(2).cross(lever);
    jac.col(i + 4) = (before.linear() * c.after_rz.linear().col(1)).cross(lever);
    jac.col(i + 5) = (before.linear() * c.after_ry.linear().col(0)).cross(lever);
  }
  for (int j = 0; j < kJointCount; ++j) {
    const Eigen::Isometry3d& before = frames[2 * j];
    const int i = jointParamIndex(j);
    jac.col(i) = before.linear().col(2).cross(ball - before.translation());
    jac.col(i + 1) = jac.col(i) * (readings[j] * kRadPerDeg);
  }
  return ball;
}

double Kinematics::barLength(const JointsDeg& readings, const Eigen::Vector3d& ball_mm,
                             const Eigen::Vector3d& chuck_mm) const {
  return (ballPosition(readings, ball_mm) - chuck_mm).norm();
}

double Kinematics::barLengthGradient(const JointsDeg& readings, const Eigen::Vector3d& ball_mm,
                                     const Eigen::Vector3d& chuck_mm, ParamRow& gradient) const {
  PositionJacobian jac;
  const Eigen::Vector3d bar = ballPositionJacobian(readings, ball_mm, jac) - chuck_mm;
  const double length = bar.norm();
  gradient.noalias() = (bar / length).transpose() * jac;
  return length;
}

JointJacobian Kinematics::jointJacobian(const JointsDeg& readings,
                                        const Eigen::Vector3d& tool_point_mm) const {
  const auto frames = chainFrames(readings);
  const Eigen::Vector3d point = frames.back() * tool_point_mm;
  JointJacobian jac;
  for (int j = 0; j < kJointCount; ++j) {
    const Eigen::Isometry3d& before = frames[2 * j];
    const double gain = params_[jointParamIndex(j) + 1];
    const Eigen::Vector3d axis = before.linear().col(2);
    jac.block<3, 1>(0, j) = gain * axis.cross(point - before.translation());
    jac.block<3, 1>(3, j) = gain * axis;
  }
  return jac;
}

}  // namespace robocal
