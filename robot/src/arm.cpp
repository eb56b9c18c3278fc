#include <robocal/robot/arm.hpp>

#include <robocal/kinematics/units.hpp>
#include <robocal/robot/numeric_ik.hpp>
#include <robocal/robot/puma_ik.hpp>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace robocal {
namespace {

// The pose error of `q` as (mm, orientation_scale_mm * rad), and its two parts.
struct PoseError {
  Eigen::Matrix<double, 6, 1> e;
  double position_mm = 0;
  double angle_rad = 0;
};

PoseError poseError(const Kinematics& kin, const Eigen::Isometry3d& target, const JointsDeg& q,
                    double orientation_scale_mm) {
  const Eigen::Isometry3d pose = kin.toolPose(q);
  PoseError out;
  out.e.head<3>() = target.translation() - pose.translation();
  const Eigen::AngleAxisd rot(target.linear() * pose.linear().transpose());
  out.e.tail<3>() = rot.axis() * (rot.angle() * orientation_scale_mm);
  out.position_mm = out.e.head<3>().norm();
  out.angle_rad = std::abs(rot.angle());
  return out;
}

// The point of line (a, u) nearest line (b, v); `a` when the lines are parallel.
Eigen::Vector3d nearestPointOn(const Eigen::Vector3d& a, const Eigen::Vector3d& u,
                               const Eigen::Vector3d& b, const Eigen::Vector3d& v) {
  const double uv = u.dot(v), den = 1.0 - uv * uv;  // unit directions
  if (den < 1e-12) return a;
  const Eigen::Vector3d w = a - b;
  const double t = (uv * v.dot(w) - u.dot(w)) / den;
  return a + t * u;
}

Eigen::Vector3d acrossAxis(const Eigen::Vector3d& v, const Eigen::Vector3d& axis) {
  return v - v.dot(axis) * axis;
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

std::string armConfigNames() {
  std::string names;
  for (int i = 0; i < kArmConfigCount; ++i)
    names += (i ? ", " : "") + armConfigName(armConfigFromIndex(i));
  return names;
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

ArmConfig ArmGeometry::config() const {
  // The signs make the PUMA's names (puma_ik.cpp's closed form) for a PUMA-like model
  // (tests/robot/test_arm.cpp compares them at random joints).
  ArmConfig c;
  c.left = shoulder_mm < 0;
  c.elbow_down = (elbow > 0) == (shoulder_mm > 0);
  c.wrist_flip = wrist < 0;
  return c;
}

ArmGeometry armGeometry(const Kinematics& kin, const JointsDeg& q) {
  const ChainFrames f = kin.chainFrames(q);
  // Joint k's axis (0-based): the z axis of the frame after J_k, through its origin.
  auto axis = [&](int k) -> Eigen::Vector3d { return f[2 * k + 1].linear().col(2); };
  auto origin = [&](int k) -> Eigen::Vector3d { return f[2 * k + 1].translation(); };
  const Eigen::Vector3d w = nearestPointOn(origin(3), axis(3), origin(4), axis(4));
  ArmGeometry g;

  Eigen::Vector3d normal = axis(0).cross(axis(1));
  if (normal.norm() < 1e-9) normal = axis(1).unitOrthogonal();  // joints 1 and 2 parallel
  g.shoulder_mm = (w - origin(0)).dot(normal.normalized());

  const Eigen::Vector3d upper = acrossAxis(origin(2) - origin(1), axis(2));
  const Eigen::Vector3d fore = acrossAxis(w - origin(2), axis(2));
  const double lengths = upper.norm() * fore.norm();
  const double sine = lengths > 0 ? axis(2).dot(upper.cross(fore)) / lengths : 0.0;
  const double cosine = lengths > 0 ? upper.dot(fore) / lengths : 1.0;
  g.elbow = sine;

  g.wrist = axis(4).dot(axis(3).cross(axis(5)));

  g.margins.shoulder_mm = std::abs(g.shoulder_mm);
  g.margins.elbow_deg = std::atan2(std::abs(sine), std::abs(cosine)) * kDegPerRad;
  g.margins.wrist_deg = std::acos(std::min(1.0, std::abs(axis(3).dot(axis(5))))) * kDegPerRad;
  return g;
}

Arm::Arm(const Model& model) : model_(model), kin_(model) {
  for (int j = 0; j < kJointCount; ++j)
    if (!(std::abs(model.joints[j].gain) > 1e-6))
      throw std::invalid_argument("model '" + model.name + "': joint " + std::to_string(j + 1) +
                                  " has a zero gain");
}

ArmConfig Arm::configOf(const JointsDeg& q) const {
  return armGeometry(kin_, q).config();
}

SingularityMargins Arm::singularityMargins(const JointsDeg& q) const {
  return armGeometry(kin_, q).margins;
}

std::array<IkSolution, kArmConfigCount> Arm::solveAll(const Eigen::Isometry3d& tool_pose) const {
  std::array<IkSolution, kArmConfigCount> out;
  for (int i = 0; i < kArmConfigCount; ++i) out[i] = solve(tool_pose, armConfigFromIndex(i));
  return out;
}

bool Arm::wrapIntoLimits(JointsDeg& q, const JointsDeg* near) const {
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

void Arm::measureError(IkSolution& s, const Eigen::Isometry3d& target) const {
  const PoseError e = poseError(kin_, target, s.joints_deg, refine_options_.orientation_scale_mm);
  s.position_error_mm = e.position_mm;
  s.angle_error_deg = e.angle_rad * kDegPerRad;
}

double Arm::poseCost(const Eigen::Isometry3d& target, const JointsDeg& q) const {
  return poseError(kin_, target, q, refine_options_.orientation_scale_mm).e.squaredNorm();
}

void Arm::judgeConverged(IkSolution& s, const Eigen::Isometry3d& target,
                         const JointsDeg* near) const {
  constexpr double kSingularEps = 1e-9;  // rad, mm: the configuration is undefined
  const SingularityMargins m = singularityMargins(s.joints_deg);
  if (m.wrist_deg < kSingularEps * kDegPerRad || m.elbow_deg < kSingularEps * kDegPerRad ||
      m.shoulder_mm < kSingularEps) {
    s.status = IkStatus::kSingular;
    return;
  }
  JointsDeg q = s.joints_deg;
  if (wrapIntoLimits(q, near ? near : &s.joints_deg)) {
    s.joints_deg = q;
    measureError(s, target);
    s.status = IkStatus::kOk;
  } else {
    s.status = IkStatus::kOutsideLimits;
  }
}

Arm::Descent Arm::descend(const Eigen::Isometry3d& target, const ArmConfig* config,
                          const JointsDeg& seed) const {
  const IkOptions& opt = refine_options_;
  Descent d;
  d.q = seed;
  PoseError err = poseError(kin_, target, d.q, opt.orientation_scale_mm);
  if (!err.e.allFinite()) return d;
  d.cost = err.e.squaredNorm();
  // Damping relative to the largest diagonal of J^T J: a Gauss-Newton step while the steps
  // lower the error (quadratic convergence near the solution), shorter and turned towards the
  // gradient while they do not. No step is taken that raises the error, so that the descent
  // cannot wander, and none longer than max_step_deg in a joint.
  double mu = 1e-9;
  while (d.iterations < opt.max_iterations) {
    if (err.position_mm < opt.position_tol_mm && err.angle_rad < opt.angle_tol_rad) {
      d.converged = true;
      return d;
    }
    ++d.iterations;
    JointJacobian jac = kin_.jointJacobian(d.q);
    jac.bottomRows<3>() *= opt.orientation_scale_mm;
    jac *= kRadPerDeg;  // per degree of reading
    const Eigen::Matrix<double, 6, 6> jtj = jac.transpose() * jac;
    const Eigen::Matrix<double, 6, 1> gradient = jac.transpose() * err.e;
    const double scale = jtj.diagonal().maxCoeff();
    const bool keep_config = config && configOf(d.q) == *config;
    bool accepted = false;
    while (!accepted && d.iterations <= opt.max_iterations) {
      Eigen::Matrix<double, 6, 6> a = jtj;
      a.diagonal().array() += mu * scale;
      Eigen::Matrix<double, 6, 1> step = a.ldlt().solve(gradient);
      const double largest = step.cwiseAbs().maxCoeff();
      if (!(largest > 1e-13)) break;  // no step left: stationary (or a non-finite Jacobian)
      if (largest > opt.max_step_deg) step *= opt.max_step_deg / largest;
      const JointsDeg next = d.q + step;
      const PoseError next_err = poseError(kin_, target, next, opt.orientation_scale_mm);
      const double next_cost = next_err.e.squaredNorm();
      if (next_err.e.allFinite() && next_cost < d.cost &&
          (!keep_config || configOf(next) == *config)) {
        d.q = next;
        d.cost = next_cost;
        err = next_err;
        mu = std::max(mu * 0.1, 1e-12);
        accepted = true;
      } else {
        mu *= 10;
        ++d.iterations;
        if (mu > 1e12) break;
      }
    }
    if (!accepted) break;  // no step lowers the error: a stationary point (or the cap)
  }
  d.converged = err.position_mm < opt.position_tol_mm && err.angle_rad < opt.angle_tol_rad;
  return d;
}

std::vector<JointsDeg> wholeRangeJoints(const Arm& arm, std::size_t count, std::uint64_t seed,
                                        double min_wrist_deg) {
  const Model& model = arm.model();
  std::mt19937_64 rng(seed);
  std::vector<JointsDeg> out;
  out.reserve(count);
  for (std::size_t draw = 0; out.size() < count && draw < 100 * count; ++draw) {
    JointsDeg q;
    for (int j = 0; j < kJointCount; ++j)
      q[j] = std::uniform_real_distribution<double>(model.joints[j].min_deg,
                                                    model.joints[j].max_deg)(rng);
    if (arm.singularityMargins(q).wrist_deg < min_wrist_deg) continue;
    out.push_back(q);
  }
  return out;
}

std::shared_ptr<const Arm> makeArm(const Model& model) {
  if (PumaIk::isPumaChain(model)) {
    auto puma = std::make_shared<const PumaIk>(model);  // made once, judged by its own miss
    if (puma->closedFormServes()) return puma;
  }
  return std::make_shared<NumericIk>(model);
}

}  // namespace robocal
