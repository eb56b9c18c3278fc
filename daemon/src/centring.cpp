#include "centring.hpp"

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/units.hpp>
#include <robocal/planner/check.hpp>
#include <robocal/solver/calibrate.hpp>

#include <Eigen/LU>

#include <cmath>
#include <limits>

namespace robocal::daemon {
Centring::Centring(const Model& nominal, const CellConfig& cell, bool enabled,
                   std::vector<Sample> samples)
    : nominal_(nominal), cell_(cell), enabled_(enabled), samples_(std::move(samples)) {
  if (enabled_ && !samples_.empty()) refit();
}

void Centring::refit() {
  const ModelUncertainty& u = cell_.uncertainty;
  const ParamVector sigma = paramSigmas(u.translation_sigma_mm, u.link_angle_sigma_deg,
                                        u.joint_offset_sigma_deg, u.gain_sigma);
  SolveOptions opt;
  opt.prior_sigma = 3.0 * sigma;  // generous: the prior only steadies what data cannot see
  opt.max_iterations = 20;
  refined_ = withParams(nominal_, solveCalibration(nominal_, samples_, opt).params);
  refined_at_ = samples_.size();
}

Eigen::Vector3d barDirection(const Model& model, const Connection& c, const JointsDeg& q) {
  const Eigen::Vector3d ball = Kinematics(model).ballPosition(q, model.balls_mm[c.ball_index]);
  return (ball - model.chucks_mm[c.chuck_index]).normalized();
}

double barLengthMm(const Model& model, const Connection& c, const JointsDeg& q) {
  const Eigen::Vector3d ball = Kinematics(model).ballPosition(q, model.balls_mm[c.ball_index]);
  return (ball - model.chucks_mm[c.chuck_index]).norm();
}

std::optional<JointsDeg> ballMove(const Model& model, const CellConfig& cell,
                                  const ShellPlan& shell, const JointsDeg& q,
                                  const Eigen::Vector3d& move_mm, std::string& problem) {
  const Connection& c = shell.connection;
  const Kinematics kin(model);
  const Eigen::Matrix<double, 3, 6> jac =
      kin.jointJacobian(q, model.balls_mm[c.ball_index]).topRows<3>();
  const Eigen::Matrix<double, 6, 1> dq =
      jac.transpose() * (jac * jac.transpose()).partialPivLu().solve(move_mm);
  const JointsDeg target = q + dq / kRadPerDeg;
  constexpr double kMaxTurnDegPerMm = 2.0;
  const double max_turn_deg = (dq / kRadPerDeg).cwiseAbs().maxCoeff();
  if (!target.allFinite() || max_turn_deg > kMaxTurnDegPerMm * std::max(1.0, move_mm.norm()))
    problem = "it would turn a joint by " + std::to_string(max_turn_deg) + " deg";
  else
    problem = ShellPlanner(model, cell)
                  .poseProblem(c, shell.radius_mm, target, std::numeric_limits<double>::infinity());
  if (!problem.empty()) return std::nullopt;
  return target;
}

std::optional<JointsDeg> correction(const Model& model, const CellConfig& cell,
                                    const ShellPlan& shell, const JointsDeg& q,
                                    double deflection_mm, std::string& problem) {
  return ballMove(model, cell, shell, q, -deflection_mm * barDirection(model, shell.connection, q),
                  problem);
}

}  // namespace robocal::daemon
