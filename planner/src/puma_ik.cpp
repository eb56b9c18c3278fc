#include <robocal/planner/puma_ik.hpp>

#include <robocal/kinematics/units.hpp>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace robocal {
namespace {

constexpr double kPi = std::numbers::pi;
// Closed-form quantities closer than this to a singularity make the configuration undefined.
constexpr double kSingularEps = 1e-9;
// How far (deg) a link rotation of the model may be from the PUMA's alpha.
constexpr double kAlphaToleranceDeg = 5.0;

double angleDistanceDeg(double a, double b) {
  return std::abs(std::remainder(a - b, 360.0));
}

}  // namespace

ArmConfig armConfigFromIndex(int index) {
  return {(index & 4) != 0, (index & 2) != 0, (index & 1) != 0};
}

int armConfigIndex(const ArmConfig& c) {
  return (c.left ? 4 : 0) | (c.elbow_down ? 2 : 0) | (c.wrist_flip ? 1 : 0);
}

std::string armConfigName(const ArmConfig& c) {
  return std::string(c.left ? "left" : "right") + (c.elbow_down ? "-down" : "-up") +
         (c.wrist_flip ? "-flip" : "-noflip");
}

std::optional<ArmConfig> parseArmConfig(const std::string& name) {
  for (int i = 0; i < kArmConfigCount; ++i)
    if (armConfigName(armConfigFromIndex(i)) == name) return armConfigFromIndex(i);
  return std::nullopt;
}

const char* ikStatusName(IkStatus status) {
  switch (status) {
    case IkStatus::kOk:
      return "ok";
    case IkStatus::kUnreachable:
      return "unreachable";
    case IkStatus::kSingular:
      return "singular";
    case IkStatus::kOutsideLimits:
      return "outside joint limits";
    case IkStatus::kNoConvergence:
      return "no convergence";
  }
  return "?";
}

PumaIk::PumaIk(const Model& model) : model_(model), kin_(model) {
  const std::array<double, 5> alphas = {90, 0, -90, 90, -90};
  for (int k = 1; k <= 5; ++k) {
    const LinkParams& l = model.links[k];
    if (angleDistanceDeg(l.rx_deg, alphas[k - 1]) > kAlphaToleranceDeg ||
        angleDistanceDeg(l.ry_deg, 0) > kAlphaToleranceDeg ||
        angleDistanceDeg(l.rz_deg, 0) > kAlphaToleranceDeg)
      throw std::invalid_argument("model '" + model.name + "': link L" + std::to_string(k) +
                                  " is not a PUMA 560 link (rotations far from the DH alphas)");
  }
  for (int j = 0; j < kJointCount; ++j)
    if (!(std::abs(model.joints[j].gain) > 1e-6))
      throw std::invalid_argument("model '" + model.name + "': joint " + std::to_string(j + 1) +
                                  " has a zero gain");
  base_inv_ = linkTransform(model.links[0]).inverse();
  tool_inv_ = linkTransform(model.links[6]).inverse();
  a2_ = model.links[2].x_mm;
  a3_ = model.links[3].x_mm;
  d3_ = model.links[3].z_mm;
  d4_ = model.links[4].z_mm;
  if (!(a2_ > 1.0) || !(d4_ > 1.0))
    throw std::invalid_argument("model '" + model.name +
                                "': upper arm or forearm length not positive");
  forearm_len_ = std::hypot(a3_, d4_);
  forearm_angle_ = std::atan2(d4_, a3_);
}

double PumaIk::theta(int j, double reading_deg) const {
  return (model_.joints[j].offset_deg + model_.joints[j].gain * reading_deg) * kRadPerDeg;
}

double PumaIk::reading(int j, double theta_rad) const {
  return (theta_rad * kDegPerRad - model_.joints[j].offset_deg) / model_.joints[j].gain;
}

bool PumaIk::wrapIntoLimits(JointsDeg& q, const JointsDeg* near) const {
  bool all_inside = true;
  for (int j = 0; j < kJointCount; ++j) {
    const JointParams& jp = model_.joints[j];
    const double period = 360.0 / std::abs(jp.gain);
    const double target = near ? (*near)[j] : 0.5 * (jp.min_deg + jp.max_deg);
    // The turn closest to the target, then the nearest turns either side of it.
    const double base = q[j] + period * std::round((target - q[j]) / period);
    double best = base, best_cost = INFINITY;
    for (int k = -3; k <= 3; ++k) {
      const double c = base + k * period;
      const double outside = std::max({0.0, jp.min_deg - c, c - jp.max_deg});
      const double cost = outside * 1e6 + std::abs(c - target);
      if (cost < best_cost) {
        best_cost = cost;
        best = c;
      }
    }
    q[j] = best;
    if (best < jp.min_deg || best > jp.max_deg) all_inside = false;
  }
  return all_inside;
}

void PumaIk::measureError(IkSolution& s, const Eigen::Isometry3d& target) const {
  const Eigen::Isometry3d pose = kin_.toolPose(s.joints_deg);
  s.position_error_mm = (pose.translation() - target.translation()).norm();
  const Eigen::AngleAxisd rot(target.linear() * pose.linear().transpose());
  s.angle_error_deg = std::abs(rot.angle()) * kDegPerRad;
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

IkSolution PumaIk::refine(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                          const JointsDeg& seed) const {
  IkSolution s;
  s.config = config;
  s.joints_deg = seed;
  const auto q = solveIk(kin_, tool_pose, seed, refine_options_);
  if (!q || !q->allFinite()) {
    measureError(s, tool_pose);
    s.status = IkStatus::kNoConvergence;
    return s;
  }
  s.joints_deg = *q;
  measureError(s, tool_pose);
  const SingularityMargins m = singularityMargins(*q);
  if (m.wrist_deg < kSingularEps * kDegPerRad || m.elbow_deg < kSingularEps * kDegPerRad ||
      m.shoulder_mm < kSingularEps) {
    s.status = IkStatus::kSingular;
  } else if (!(configOf(*q) == config)) {
    s.status = IkStatus::kNoConvergence;
  } else {
    s.status = withinLimits(model_, *q) ? IkStatus::kOk : IkStatus::kOutsideLimits;
  }
  return s;
}

IkSolution PumaIk::solve(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                         const JointsDeg* near) const {
  IkSolution cf = closedForm(tool_pose, config, near);
  if (cf.status == IkStatus::kUnreachable || cf.status == IkStatus::kSingular) return cf;
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

std::array<IkSolution, kArmConfigCount> PumaIk::solveAll(const Eigen::Isometry3d& tool_pose) const {
  std::array<IkSolution, kArmConfigCount> out;
  for (int i = 0; i < kArmConfigCount; ++i) out[i] = solve(tool_pose, armConfigFromIndex(i));
  return out;
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
