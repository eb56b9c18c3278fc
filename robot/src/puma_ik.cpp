#include <robocal/robot/puma_ik.hpp>

#include <robocal/kinematics/units.hpp>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <tuple>

namespace robocal {
namespace {

constexpr double kPi = std::numbers::pi;
// Closed-form quantities closer than this to a singularity make the configuration undefined.
constexpr double kSingularEps = 1e-9;
// A refinement that stops short of the target this close to the elbow's or the shoulder's
// singularity may have found the edge of the arm's reach (refine()).
constexpr double kBoundaryElbowDeg = 1.0;
constexpr double kBoundaryShoulderMm = 5.0;
// How far (deg) a link rotation of the model may be from the PUMA's alpha.
constexpr double kAlphaToleranceDeg = 5.0;
// How far the closed form may miss a pose of a model it fits (a calibration moves links by a
// few millimetres and tenths of a degree; the refinement starts from there).
constexpr double kFitsPositionMm = 20.0;
constexpr double kFitsAngleDeg = 2.0;

double angleDistanceDeg(double a, double b) {
  return std::abs(std::remainder(a - b, 360.0));
}

// Why the model is not a chain the closed form serves; empty when it is.
std::string pumaChainProblem(const Model& model) {
  const std::array<double, 5> alphas = {90, 0, -90, 90, -90};
  for (int k = 1; k <= 5; ++k) {
    const LinkParams& l = model.links[k];
    if (angleDistanceDeg(l.rx_deg, alphas[k - 1]) > kAlphaToleranceDeg ||
        angleDistanceDeg(l.ry_deg, 0) > kAlphaToleranceDeg ||
        angleDistanceDeg(l.rz_deg, 0) > kAlphaToleranceDeg)
      return "model '" + model.name + "': link L" + std::to_string(k) +
             " is not a PUMA 560 link (rotations far from the DH alphas)";
  }
  if (!(model.links[2].x_mm > 1.0) || !(model.links[4].z_mm > 1.0))
    return "model '" + model.name + "': upper arm or forearm length not positive";
  return {};
}

}  // namespace

bool PumaIk::isPumaChain(const Model& model) {
  return pumaChainProblem(model).empty();
}

bool PumaIk::closedFormServes() const {
  // The closed form must land near enough for the refinement to start from it: a chain with the
  // PUMA's joint axes but other offsets (a shoulder offset along L1.x, as the Staubli RX arms
  // have) is not one it solves.
  return miss_mm_ <= kFitsPositionMm && miss_deg_ <= kFitsAngleDeg;
}

std::pair<double, double> PumaIk::closedFormMiss() const {
  const double probes[][kJointCount] = {
      {10, -30, 40, 20, 50, 30}, {-60, -80, 150, -40, -30, 70}, {120, 20, -20, 90, 70, -100}};
  double miss_mm = 0, miss_deg = 0;
  for (const auto& probe : probes) {
    const JointsDeg q = Eigen::Map<const JointsDeg>(probe);
    const IkSolution cf = closedForm(kin_.toolPose(q), configOf(q));
    if (cf.status != IkStatus::kOk && cf.status != IkStatus::kOutsideLimits)
      return {INFINITY, INFINITY};
    miss_mm = std::max(miss_mm, cf.position_error_mm);
    miss_deg = std::max(miss_deg, cf.angle_error_deg);
  }
  return {miss_mm, miss_deg};
}

PumaIk::PumaIk(const Model& model) : Arm(model) {
  if (const std::string problem = pumaChainProblem(model); !problem.empty())
    throw std::invalid_argument(problem);
  base_inv_ = linkTransform(model.links[0]).inverse();
  tool_inv_ = linkTransform(model.links[6]).inverse();
  a2_ = model.links[2].x_mm;
  a3_ = model.links[3].x_mm;
  d3_ = model.links[3].z_mm;
  d4_ = model.links[4].z_mm;
  forearm_len_ = std::hypot(a3_, d4_);
  forearm_angle_ = std::atan2(d4_, a3_);
  std::tie(miss_mm_, miss_deg_) = closedFormMiss();
}

double PumaIk::theta(int j, double reading_deg) const {
  return jointAngleRad(model_.joints[j].offset_deg * kRadPerDeg, model_.joints[j].gain,
                       reading_deg);
}

double PumaIk::reading(int j, double theta_rad) const {
  return jointReadingDeg(model_.joints[j].offset_deg * kRadPerDeg, model_.joints[j].gain,
                         theta_rad);
}

IkSolution PumaIk::closedForm(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                              const JointsDeg* near) const {
  IkSolution s;
  s.config = config;
  const Eigen::Isometry3d t06 = base_inv_ * tool_pose * tool_inv_;
  const Eigen::Vector3d p = t06.translation();
  if (!p.allFinite() || !t06.linear().allFinite()) return s;  // kUnreachable, zero joints

  std::array<double, 6> th{};
  // Joint 1: r sin(theta1 - phi) = d3.
  const double r2 = p.x() * p.x() + p.y() * p.y();
  if (r2 < d3_ * d3_) return s;  // inside the shoulder offset's cylinder
  const double r = std::sqrt(r2);
  const double phi = std::atan2(p.y(), p.x());
  const double delta = std::asin(std::clamp(d3_ / r, -1.0, 1.0));
  th[0] = config.left ? phi + kPi - delta : phi + delta;
  const double u = std::cos(th[0]) * p.x() + std::sin(th[0]) * p.y();
  const double v = p.z();
  bool singular = std::abs(u) < kSingularEps;

  // Joint 3: a3 c3 - d4 s3 = L3 cos(theta3 + beta) = K.
  const double k = (u * u + v * v - a2_ * a2_ - forearm_len_ * forearm_len_) / (2.0 * a2_);
  const double c = k / forearm_len_;
  if (std::abs(c) > 1.0 + 1e-12) return s;
  const double bend = std::acos(std::clamp(c, -1.0, 1.0));
  if (bend < kSingularEps || bend > kPi - kSingularEps) singular = true;
  bool found = false;
  for (const double sign : {1.0, -1.0}) {
    const double t3 = -forearm_angle_ + sign * bend;
    const double x = a2_ + a3_ * std::cos(t3) - d4_ * std::sin(t3);
    const double y = a3_ * std::sin(t3) + d4_ * std::cos(t3);
    const double t2 = std::atan2(v, u) - std::atan2(y, x);
    const double cross = u * a2_ * std::sin(t2) - v * a2_ * std::cos(t2);
    const bool elbow_up = (cross > 0) == (u > 0);
    if (elbow_up == !config.elbow_down) {
      th[1] = t2;
      th[2] = t3;
      found = true;
      break;
    }
  }
  if (!found) {  // both branches coincide (straight arm): take the first one
    th[2] = -forearm_angle_ + bend;
    const double x = a2_ + a3_ * std::cos(th[2]) - d4_ * std::sin(th[2]);
    const double y = a3_ * std::sin(th[2]) + d4_ * std::cos(th[2]);
    th[1] = std::atan2(v, u) - std::atan2(y, x);
    singular = true;
  }

  // Wrist: R36 = Rz(theta4) Ry(-theta5) Rz(theta6).
  const Eigen::Matrix3d r03 = (Eigen::AngleAxisd(th[0], Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitX()) *
                               Eigen::AngleAxisd(th[1] + th[2], Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(-kPi / 2, Eigen::Vector3d::UnitX()))
                                  .toRotationMatrix();
  const Eigen::Matrix3d r36 = r03.transpose() * t06.linear();
  const double s5_abs = std::hypot(r36(0, 2), r36(1, 2));
  const double sigma = config.wrist_flip ? -1.0 : 1.0;
  if (s5_abs < kSingularEps) {
    singular = true;
    // Axes 4 and 6 aligned: only theta4 + theta6 (or theta4 - theta6) is defined; keep theta4.
    th[3] = near ? theta(3, (*near)[3]) : 0.0;
    th[4] = r36(2, 2) > 0 ? 0.0 : kPi;
    const double sum = std::atan2(r36(1, 0), r36(0, 0));
    th[5] = r36(2, 2) > 0 ? sum - th[3] : th[3] - sum;
  } else {
    th[4] = std::atan2(sigma * s5_abs, r36(2, 2));
    th[3] = std::atan2(-sigma * r36(1, 2), -sigma * r36(0, 2));
    th[5] = std::atan2(-sigma * r36(2, 1), sigma * r36(2, 0));
  }

  for (int j = 0; j < kJointCount; ++j) s.joints_deg[j] = reading(j, th[j]);
  const bool inside = wrapIntoLimits(s.joints_deg, near);
  if (!s.joints_deg.allFinite()) {
    s.joints_deg.setZero();
    s.status = IkStatus::kUnreachable;
    return s;
  }
  measureError(s, tool_pose);
  s.status = singular ? IkStatus::kSingular : inside ? IkStatus::kOk : IkStatus::kOutsideLimits;
  return s;
}

std::optional<JointsDeg> PumaIk::closedFormSeed(const Eigen::Isometry3d& target,
                                                const ArmConfig& config,
                                                const JointsDeg& near) const {
  // The closed form is exact for the DH part of the model; for the rest, aim it at a target
  // moved by the pose error its previous answer left (a fixed-point iteration that contracts
  // as fast as the model is close to its DH arm).
  Eigen::Isometry3d aim = target;
  std::optional<JointsDeg> best;
  double best_cost = INFINITY;
  for (int k = 0; k < 6; ++k) {
    const IkSolution cf = closedForm(aim, config, &near);
    if (cf.status != IkStatus::kOk && cf.status != IkStatus::kOutsideLimits) break;
    const Eigen::Isometry3d pose = kin_.toolPose(cf.joints_deg);
    const double cost = poseCost(target, cf.joints_deg);
    if (!(cost < best_cost)) break;
    best = cf.joints_deg;
    best_cost = cost;
    aim = aim * pose.inverse() * target;
  }
  return best;
}

IkSolution PumaIk::refine(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                          const JointsDeg& seed) const {
  IkSolution s;
  s.config = config;
  s.joints_deg = seed.allFinite() ? seed : JointsDeg::Zero();
  if (!tool_pose.matrix().allFinite()) {
    s.status = IkStatus::kUnreachable;
    return s;
  }
  auto found = [&](const Descent& d) { return Arm::found(d, config); };
  Descent d = descend(tool_pose, &config, s.joints_deg);
  if (!found(d)) {
    // From a seed across a singularity of this model (the elbow or the shoulder plane moved
    // with the calibration), or too far for the descent: again from the closed form of this
    // model's own geometry.
    if (const auto cf = closedFormSeed(tool_pose, config, s.joints_deg)) {
      const Descent again = descend(tool_pose, &config, *cf);
      if (found(again) || again.cost < d.cost) d = again;
    }
  }
  s.joints_deg = d.q.allFinite() ? d.q : s.joints_deg;
  measureError(s, tool_pose);
  if (!found(d)) {
    // A descent that stops short of the target with the arm stretched straight (or the wrist
    // centre on joint 1's axis plane) has found the nearest pose the configuration reaches: the
    // target is out of its reach. Unless a descent free to change the configuration reaches it
    // from there: then the target is in reach (near enough alike for all configurations of a
    // PUMA-like arm) and the iteration failed. Anything else is a failure of the iteration.
    const SingularityMargins m = singularityMargins(s.joints_deg);
    const bool at_boundary =
        !d.converged && d.q.allFinite() &&
        (m.elbow_deg < kBoundaryElbowDeg || m.shoulder_mm < kBoundaryShoulderMm);
    s.status = at_boundary && !descend(tool_pose, nullptr, d.q).converged
                   ? IkStatus::kUnreachable
                   : IkStatus::kNoConvergence;
    return s;
  }
  const SingularityMargins m = singularityMargins(d.q);
  if (m.wrist_deg < kSingularEps * kDegPerRad || m.elbow_deg < kSingularEps * kDegPerRad ||
      m.shoulder_mm < kSingularEps) {
    s.status = IkStatus::kSingular;
  } else {
    s.status = withinLimits(model_, d.q) ? IkStatus::kOk : IkStatus::kOutsideLimits;
  }
  return s;
}

IkSolution PumaIk::solve(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                         const JointsDeg* near) const {
  IkSolution cf = closedForm(tool_pose, config, near);
  if (cf.status == IkStatus::kUnreachable || cf.status == IkStatus::kSingular) {
    // The closed form solves the model's DH part. A calibrated model reaches a little further or
    // less far than that, and is singular a little elsewhere: near the edge of the reach or a
    // singularity the closed form can say no where the model has an answer.
    if (miss_mm_ < 1e-6) return cf;  // the closed form solves the full model
    const IkSolution seeded = solveFromSeeds(tool_pose, config, near);
    return seeded.ok() ? seeded : cf;
  }
  if (cf.position_error_mm < 1e-6 && cf.angle_error_deg < 1e-8) return cf;  // exact DH model
  IkSolution s = refine(tool_pose, config, cf.joints_deg);
  if (s.status == IkStatus::kOutsideLimits) {  // the refinement may have crossed a limit's turn
    JointsDeg q = s.joints_deg;
    if (wrapIntoLimits(q, near ? near : &cf.joints_deg)) {
      s.joints_deg = q;
      measureError(s, tool_pose);
      s.status = IkStatus::kOk;
    }
  }
  return s;
}

ArmConfig PumaIk::configOf(const JointsDeg& q) const {
  const double t2 = theta(1, q[1]), t23 = t2 + theta(2, q[2]);
  const double u = a2_ * std::cos(t2) + a3_ * std::cos(t23) - d4_ * std::sin(t23);
  const double v = a2_ * std::sin(t2) + a3_ * std::sin(t23) + d4_ * std::cos(t23);
  const double cross = u * a2_ * std::sin(t2) - v * a2_ * std::cos(t2);
  ArmConfig c;
  c.left = u < 0;
  c.elbow_down = !((cross > 0) == (u > 0));
  c.wrist_flip = std::sin(theta(4, q[4])) < 0;
  return c;
}

SingularityMargins PumaIk::singularityMargins(const JointsDeg& q) const {
  const double t2 = theta(1, q[1]), t3 = theta(2, q[2]), t23 = t2 + t3;
  SingularityMargins m;
  m.wrist_deg = std::acos(std::min(1.0, std::abs(std::cos(theta(4, q[4]))))) * kDegPerRad;
  m.elbow_deg = std::acos(std::min(1.0, std::abs(std::cos(t3 + forearm_angle_)))) * kDegPerRad;
  m.shoulder_mm = std::abs(a2_ * std::cos(t2) + a3_ * std::cos(t23) - d4_ * std::sin(t23));
  return m;
}

}  // namespace robocal
