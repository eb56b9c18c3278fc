#include <robocal/kinematics/ik.hpp>

#include <robocal/kinematics/units.hpp>

#include <Eigen/LU>

namespace robocal {

std::optional<JointsDeg> solveIk(const Kinematics& kin, const Eigen::Isometry3d& target,
                                 const JointsDeg& seed, const IkOptions& opt) {
  JointsDeg q = seed;
  const double damping = 1e-3;
  for (int it = 0; it < opt.max_iterations; ++it) {
    const Eigen::Isometry3d pose = kin.toolPose(q);
    Eigen::Matrix<double, 6, 1> err;
    err.head<3>() = target.translation() - pose.translation();
    const Eigen::AngleAxisd rot(target.linear() * pose.linear().transpose());
    err.tail<3>() = rot.axis() * rot.angle();
    if (!err.allFinite()) return std::nullopt;
    if (err.head<3>().norm() < opt.position_tol_mm && rot.angle() < opt.angle_tol_rad) return q;

    JointJacobian jac = kin.jointJacobian(q);
    jac.bottomRows<3>() *= opt.orientation_scale_mm;
    err.tail<3>() *= opt.orientation_scale_mm;
    const Eigen::Matrix<double, 6, 6> jjt =
        jac * jac.transpose() + damping * damping * Eigen::Matrix<double, 6, 6>::Identity();
    Eigen::Matrix<double, 6, 1> step_deg = jac.transpose() * jjt.partialPivLu().solve(err);
    step_deg *= kDegPerRad;
    const double largest = step_deg.cwiseAbs().maxCoeff();
    if (largest > opt.max_step_deg) step_deg *= opt.max_step_deg / largest;
    q += step_deg;
  }
  return std::nullopt;
}

bool withinLimits(const Model& model, const JointsDeg& readings, double margin_deg) {
  for (int j = 0; j < kJointCount; ++j) {
    if (readings[j] < model.joints[j].min_deg + margin_deg) return false;
    if (readings[j] > model.joints[j].max_deg - margin_deg) return false;
  }
  return true;
}

}  // namespace robocal
