#include <robocal/planner/plan.hpp>

#include "parallel.hpp"

#include <robocal/kinematics/ik.hpp>
#include <robocal/kinematics/path_motion.hpp>
#include <robocal/kinematics/units.hpp>
#include <robocal/solver/identifiability.hpp>
#include <robocal/solver/problem.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>

namespace robocal {
namespace {

constexpr double kPi = std::numbers::pi;
// The planner aims below the tolerance so that a re-check (which samples the same way) has room.
constexpr double kPlannerToleranceFraction = 0.9;
constexpr int kMaxBisections = 10;      // 2^10 vias at most between two data points
constexpr double kSteerExtraDeg = 5.0;  // the policy keeps the bar this far past its minimum angle
constexpr int kCoarseSamples = 8;

std::string fmt(const char* format, double a, double b = 0, double c = 0) {
  char buf[200];
  std::snprintf(buf, sizeof buf, format, a, b, c);
  return buf;
}

Eigen::Vector3d unitOnSphere(double lat_deg, double lon_deg) {
  const double lat = lat_deg * kRadPerDeg, lon = lon_deg * kRadPerDeg;
  return {std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
}

void latLonOf(const Eigen::Vector3d& n, double& lat_deg, double& lon_deg) {
  lat_deg = std::asin(std::clamp(n.z(), -1.0, 1.0)) * kDegPerRad;
  lon_deg = std::atan2(n.y(), n.x()) * kDegPerRad;
  if (lon_deg < 0) lon_deg += 360.0;
  if (std::abs(n.x()) < 1e-12 && std::abs(n.y()) < 1e-12) lon_deg = 0;
}

Eigen::Vector3d slerp(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double t) {
  const double angle = std::acos(std::clamp(a.dot(b), -1.0, 1.0));
  if (angle < 1e-9) return a;
  Eigen::Vector3d v;
  if (angle > kPi - 1e-6) {  // antipodal: go over the pole of the shell
    const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
    Eigen::Vector3d mid = (up - up.dot(a) * a);
    if (mid.norm() < 1e-9) mid = Eigen::Vector3d::UnitX() - a.x() * a;
    mid.normalize();
    const double phi = t * kPi;
    return std::cos(phi) * a + std::sin(phi) * mid;
  }
  v = (std::sin((1 - t) * angle) * a + std::sin(t * angle) * b) / std::sin(angle);
  return v.normalized();
}

using Offset = ToolOffset;

double offsetDistance(const Offset& a, const Offset& b) {
  return std::abs(std::remainder(a.yaw_deg - b.yaw_deg, 360.0)) / 45.0 +
         std::abs(a.pitch_deg - b.pitch_deg) / 20.0 +
         std::abs(std::remainder(a.roll_deg - b.roll_deg, 360.0)) / 90.0;
}

// Tool orientations tried when the policy's own is not safe, nearest first.
const std::vector<Offset>& candidateOffsets() {
  static const std::vector<Offset> list = [] {
    std::vector<Offset> v;
    for (double yaw : {0.0, 45.0, -45.0, 90.0, -90.0, 135.0, -135.0, 180.0})
      for (double pitch : {0.0, 25.0, -20.0})
        for (double roll : {0.0, 90.0, -90.0, 180.0}) v.push_back({yaw, pitch, roll});
    std::stable_sort(v.begin(), v.end(), [](const Offset& a, const Offset& b) {
      return offsetDistance(a, {0, 0, 0}) < offsetDistance(b, {0, 0, 0});
    });
    return v;
  }();
  return list;
}

}  // namespace

struct ShellPlanner::Node {
  Eigen::Vector3d n;  // unit vector from the chuck to the ball
  Eigen::Quaterniond rotation;
  JointsDeg q;
  double lat_deg, lon_deg;
  // Extra deviation allowed on moves that start here: a robot pose planned with another model
  // is off this model's shell by that much (re-planning).
  double slack_mm = 0;
};

ShellPlanner::ShellPlanner(const Model& model, const CellConfig& cell)
    : arm_([&] {
        try {
          return makeArm(model);
        } catch (const std::invalid_argument& e) {
          throw PlanError(e.what());
        }
      }()),
      cell_(cell) {
  try {
    validateCell(cell);
  } catch (const std::invalid_argument& e) {
    throw PlanError(std::string("cell: ") + e.what());
  }
  for (int j = 0; j < kJointCount; ++j) {
    const JointParams& jp = model.joints[j];
    if (jp.max_deg - jp.min_deg <= 2 * cell.margins.joint_limit_deg)
      throw PlanError(fmt("cell: margins.joint_limit_deg: %.1f deg leaves no range for joint %.0f "
                          "(limits %.1f .. ",
                          cell.margins.joint_limit_deg, j + 1.0, jp.min_deg) +
                      fmt("%.1f deg)", jp.max_deg));
  }
  joint1_origin_ = linkTransform(model.links[0]).translation();
  tool_inv_ = linkTransform(model.links[6]).inverse();
}

Eigen::Isometry3d ShellPlanner::policyPose(const Connection& c, double radius, double lat_deg,
                                           double lon_deg, double yaw_offset_deg,
                                           double pitch_offset_deg, double roll_offset_deg) const {
  const ToolOrientationPolicy& p = cell_.tool;
  const Eigen::Vector3d n = unitOnSphere(lat_deg, lon_deg);
  const Eigen::Vector3d ball = model().chucks_mm[c.chuck_index] + radius * n;
  Eigen::Vector3d h = ball - joint1_origin_;
  h.z() = 0;
  h = h.norm() > 1e-6 ? h.normalized() : Eigen::Vector3d::UnitX();
  const Eigen::Vector3d side(-h.y(), h.x(), 0);
  const double lat = lat_deg * kRadPerDeg, lon = lon_deg * kRadPerDeg;
  const double pitch =
      (p.approach_pitch_deg + pitch_offset_deg + p.pitch_variation_deg * std::sin(2 * lon + lat)) *
      kRadPerDeg;
  const double yaw =
      (p.approach_yaw_deg + yaw_offset_deg + p.yaw_variation_deg * std::sin(lon - 2 * lat)) *
      kRadPerDeg;
  const double roll =
      (p.roll_deg + roll_offset_deg + p.roll_variation_deg * std::sin(lon + 3 * lat)) * kRadPerDeg;
  Eigen::Vector3d a = std::cos(pitch) * (std::cos(yaw) * h + std::sin(yaw) * side) -
                      std::sin(pitch) * Eigen::Vector3d::UnitZ();
  // Keep the bar (direction -n from the ball) away from the tool's backward axis (-a).
  const double keep = (p.min_bar_tool_angle_deg + kSteerExtraDeg) * kRadPerDeg;
  if (n.dot(a) > std::cos(keep)) {
    Eigen::Vector3d t = a - a.dot(n) * n;
    t = t.norm() > 1e-9 ? t.normalized() : side;
    a = std::cos(keep) * n + std::sin(keep) * t;
  }
  a.normalize();
  Eigen::Vector3d x0 = Eigen::Vector3d::UnitZ() - a.z() * a;
  if (x0.norm() < 1e-6) x0 = h - h.dot(a) * a;
  x0.normalize();
  const Eigen::Vector3d x = Eigen::AngleAxisd(roll, a) * x0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear().col(0) = x;
  pose.linear().col(1) = a.cross(x);
  pose.linear().col(2) = a;
  pose.translation() = ball - pose.linear() * model().balls_mm[c.ball_index];
  return pose;
}

PoseReport ShellPlanner::inspect(const Connection& c, double radius, const JointsDeg& q) const {
  return inspectPose(c, radius, q, arm_->kinematics().toolPose(q));
}

PoseReport ShellPlanner::inspectPose(const Connection& c, double radius, const JointsDeg& q,
                                     const Eigen::Isometry3d& pose) const {
  PoseReport r;
  const Eigen::Vector3d chuck = model().chucks_mm[c.chuck_index];
  r.ball_mm = pose * model().balls_mm[c.ball_index];
  const Eigen::Vector3d bar = chuck - r.ball_mm;
  r.deviation_mm = bar.norm() - radius;
  const Eigen::Vector3d back = -pose.linear().col(2);
  r.bar_tool_angle_deg = std::acos(std::clamp(bar.normalized().dot(back), -1.0, 1.0)) * kDegPerRad;
  const Eigen::Vector3d wrist = (pose * tool_inv_).translation();
  r.min_height_mm = std::min(pose.translation().z(), wrist.z());
  // Distance of a point from the bar, the segment chuck -> ball.
  auto fromBar = [&](const Eigen::Vector3d& p) {
    const double t = std::clamp((p - chuck).dot(-bar) / bar.squaredNorm(), 0.0, 1.0);
    return (p - (chuck - t * bar)).norm();
  };
  r.bar_clearance_mm = std::min(fromBar(pose.translation()), fromBar(wrist));
  r.singularity = arm_->singularityMargins(q);
  return r;
}

std::string ShellPlanner::poseProblem(const Connection& c, double radius, const JointsDeg& q,
                                      double tolerance_mm) const {
  PoseReport r;
  return poseProblem(c, radius, q, tolerance_mm, r);
}

std::string ShellPlanner::poseProblem(const Connection& c, double radius, const JointsDeg& q,
                                      double tolerance_mm, PoseReport& r) const {
  if (!q.allFinite()) return "joints are not finite numbers";
  r = inspect(c, radius, q);
  return problemOf(q, r, tolerance_mm);
}

std::string ShellPlanner::problemOf(const JointsDeg& q, const PoseReport& r,
                                    double tolerance_mm) const {
  const SafetyMargins& m = cell_.margins;
  for (int j = 0; j < kJointCount; ++j) {
    const JointParams& jp = model().joints[j];
    if (q[j] < jp.min_deg + m.joint_limit_deg || q[j] > jp.max_deg - m.joint_limit_deg)
      return fmt("joint %.0f at %.2f deg is not %.1f deg inside its limits", j + 1.0, q[j],
                 m.joint_limit_deg);
  }
  if (r.singularity.wrist_deg < m.wrist_singularity_deg)
    return fmt("wrist %.2f deg from singular (margin %.1f deg)", r.singularity.wrist_deg,
               m.wrist_singularity_deg);
  if (r.singularity.elbow_deg < m.elbow_singularity_deg)
    return fmt("elbow %.2f deg from singular (margin %.1f deg)", r.singularity.elbow_deg,
               m.elbow_singularity_deg);
  if (r.singularity.shoulder_mm < m.shoulder_singularity_mm)
    return fmt("wrist centre %.1f mm from the shoulder singularity (margin %.1f mm)",
               r.singularity.shoulder_mm, m.shoulder_singularity_mm);
  if (r.bar_tool_angle_deg < cell_.tool.min_bar_tool_angle_deg)
    return fmt("bar %.1f deg from the tool axis (minimum %.1f deg)", r.bar_tool_angle_deg,
               cell_.tool.min_bar_tool_angle_deg);
  if (r.bar_clearance_mm < m.bar_clearance_mm)
    return fmt("flange or wrist centre %.1f mm from the bar (minimum %.1f mm)", r.bar_clearance_mm,
               m.bar_clearance_mm);
  if (r.min_height_mm < m.table_clearance_mm)
    return fmt("flange or wrist centre %.1f mm above the table plane (minimum %.1f mm)",
               r.min_height_mm, m.table_clearance_mm);
  if (std::abs(r.deviation_mm) > tolerance_mm)
    return fmt("bar deviation %+.3f mm beyond +/-%.3f mm", r.deviation_mm, tolerance_mm);
  return {};
}

bool ShellPlanner::walkSegment(
    const Connection& c, const JointsDeg& a, const JointsDeg& b,
    const std::function<bool(int, const JointsDeg&, const Eigen::Isometry3d&)>& visit,
    double length) const {
  const Kinematics& kin = arm_->kinematics();
  const Eigen::Vector3d ball = model().balls_mm[c.ball_index];
  const double step = cell_.motion.sample_step_mm;
  Eigen::Vector3d prev = kin.ballPosition(a, ball);
  // The ball's path length, from a few samples, sets the first try's sample count.
  if (length < 0) {
    length = 0;
    for (int i = 1; i <= kCoarseSamples; ++i) {
      const Eigen::Vector3d p = kin.ballPosition(a + (b - a) * (double(i) / kCoarseSamples), ball);
      length += (p - prev).norm();
      prev = p;
    }
  }
  int n = std::max(1, static_cast<int>(std::ceil(1.3 * length / step)));
  for (int attempt = 0;; ++attempt, n *= 2) {
    const bool last = attempt >= 8;  // 2^8 times the estimate: take what it gives
    bool spaced = true;
    for (int i = 0; i <= n; ++i) {
      const JointsDeg q = a + (b - a) * (double(i) / n);
      const Eigen::Isometry3d pose = kin.toolPose(q);
      const Eigen::Vector3d p = pose * ball;
      if (i > 0 && (p - prev).norm() > step && !last) {
        spaced = false;
        break;
      }
      prev = p;
      if (!visit(i, q, pose)) return false;
    }
    if (spaced) return true;
  }
}

std::vector<JointsDeg> ShellPlanner::segmentSamples(const Connection& c, const JointsDeg& a,
                                                    const JointsDeg& b) const {
  std::vector<JointsDeg> out;
  walkSegment(c, a, b, [&](int i, const JointsDeg& q, const Eigen::Isometry3d&) {
    if (i == 0) out.clear();  // a finer try starts again
    out.push_back(q);
    return true;
  });
  return out;
}

bool ShellPlanner::segmentOk(const Connection& c, double radius, const JointsDeg& a,
                             const JointsDeg& b, double tolerance_mm, double& worst,
                             std::string& why) const {
  worst = 0;
  // A cheap look first: most failing segments fail at one of a few samples, which also give
  // the path's length for the dense walk.
  const Kinematics& kin = arm_->kinematics();
  const Eigen::Vector3d ball = model().balls_mm[c.ball_index];
  double length = 0;
  Eigen::Vector3d prev = kin.ballPosition(a, ball);
  for (int i = 1; i <= kCoarseSamples; ++i) {
    const JointsDeg q = a + (b - a) * (double(i) / kCoarseSamples);
    const Eigen::Isometry3d pose = kin.toolPose(q);
    const Eigen::Vector3d p = pose * ball;
    length += (p - prev).norm();
    prev = p;
    if (i == kCoarseSamples) break;
    const std::string problem = problemOf(q, inspectPose(c, radius, q, pose), tolerance_mm);
    if (!problem.empty()) {
      why = problem;
      return false;
    }
  }
  return walkSegment(
      c, a, b,
      [&](int, const JointsDeg& q, const Eigen::Isometry3d& pose) {
        const PoseReport r = inspectPose(c, radius, q, pose);
        const std::string problem = problemOf(q, r, tolerance_mm);
        if (!problem.empty()) {
          why = problem;
          return false;
        }
        worst = std::max(worst, std::abs(r.deviation_mm));
        return true;
      },
      length);
}

ShellPlanner::Node ShellPlanner::nodeFor(const Connection& c, double radius, double lat_deg,
                                         double lon_deg, const Eigen::Isometry3d& pose,
                                         const JointsDeg& q) const {
  (void)radius;
  Node node;
  const Eigen::Vector3d ball = pose * model().balls_mm[c.ball_index];
  node.n = (ball - model().chucks_mm[c.chuck_index]).normalized();
  node.rotation = Eigen::Quaterniond(pose.linear());
  node.q = q;
  node.lat_deg = lat_deg;
  node.lon_deg = lon_deg;
  return node;
}

bool ShellPlanner::planArc(const Connection& c, double radius, const ArmConfig& config,
                           const Node& a, const Node& b, int depth, std::vector<PlanStep>& vias,
                           double& worst, std::string& why) const {
  double seg_worst = 0;
  if (segmentOk(c, radius, a.q, b.q,
                kPlannerToleranceFraction * cell_.motion.via_tolerance_mm + a.slack_mm, seg_worst,
                why)) {
    worst = std::max(worst, seg_worst);
    return true;
  }
  if (depth >= kMaxBisections) return false;
  Node mid;
  mid.slack_mm = 0;
  mid.n = slerp(a.n, b.n, 0.5);
  latLonOf(mid.n, mid.lat_deg, mid.lon_deg);
  Eigen::Quaterniond qa = a.rotation, qb = b.rotation;
  if (qa.dot(qb) < 0) qb.coeffs() *= -1;
  // The interpolated orientation first; when it is not safe, the policy's orientations at the
  // via's place, nearest to the interpolated one first.
  std::vector<Eigen::Quaterniond> rotations = {qa.slerp(0.5, qb)};
  {
    std::vector<std::pair<double, Eigen::Quaterniond>> others;
    for (const Offset& off : candidateOffsets()) {
      const Eigen::Quaterniond r(
          policyPose(c, radius, mid.lat_deg, mid.lon_deg, off.yaw_deg, off.pitch_deg, off.roll_deg)
              .linear());
      others.push_back({r.angularDistance(rotations[0]), r});
    }
    std::stable_sort(others.begin(), others.end(),
                     [](const auto& x, const auto& y) { return x.first < y.first; });
    for (size_t i = 0; i < others.size() && i < 6; ++i) rotations.push_back(others[i].second);
  }
  bool found = false;
  for (size_t r = 0; r < rotations.size() && !found; ++r) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = rotations[r].toRotationMatrix();
    pose.translation() = model().chucks_mm[c.chuck_index] + radius * mid.n -
                         pose.linear() * model().balls_mm[c.ball_index];
    const IkSolution s = arm_->solve(pose, config, &a.q);
    // A via far from both ends in joint space means a joint took another turn (a limit was in
    // the way): the moves either side would swing the bar about.
    const double span = (b.q - a.q).cwiseAbs().maxCoeff();
    if (s.ok() && (s.joints_deg - 0.5 * (a.q + b.q)).cwiseAbs().maxCoeff() > 0.5 * span + 45.0) {
      if (r == 0)
        why = fmt("via at lat %.1f lon %.1f deg: a joint would turn the long way", mid.lat_deg,
                  mid.lon_deg);
      continue;
    }
    const std::string problem =
        s.ok() ? poseProblem(c, radius, s.joints_deg, cell_.motion.via_tolerance_mm)
               : std::string(ikStatusName(s.status));
    if (!problem.empty()) {
      if (r == 0) why = fmt("via at lat %.1f lon %.1f deg: ", mid.lat_deg, mid.lon_deg) + problem;
      continue;
    }
    mid.q = s.joints_deg;
    mid.rotation = rotations[r];
    found = true;
  }
  if (!found) return false;
  if (!planArc(c, radius, config, a, mid, depth + 1, vias, worst, why)) return false;
  vias.push_back({StepKind::kVia, mid.q, mid.lat_deg, mid.lon_deg});
  return planArc(c, radius, config, mid, b, depth + 1, vias, worst, why);
}

JointsDeg approachPrePoint(const Kinematics& kin, const Eigen::Vector3d& ball,
                           const Eigen::Vector3d& chuck, const JointsDeg& q, double step_deg) {
  // Every joint steps back by step_deg; one joint steps back further so that the ball stays on
  // the shell (the bar's length changes by g . dq, g its gradient in the joints): the step alone
  // moved the ball radially by up to 0.9 mm at 0.05 deg.
  JointsDeg pre_q = q - JointsDeg::Constant(step_deg);
  const double at_q = kin.barLength(q, ball, chuck);
  JointsDeg gradient;  // mm per deg
  for (int j = 0; j < kJointCount; ++j) {
    JointsDeg moved = q;
    moved[j] += 1e-3;
    gradient[j] = (kin.barLength(moved, ball, chuck) - at_q) / 1e-3;
  }
  const double change_mm = gradient.dot(pre_q - q);
  int best = -1;  // the joint whose further step back undoes the change best
  for (int j = 0; j < kJointCount; ++j)
    if (gradient[j] * change_mm > 0 &&
        (best < 0 || std::abs(gradient[j]) > std::abs(gradient[best])))
      best = j;
  if (best >= 0) {
    pre_q[best] -= std::min(change_mm / gradient[best], 10 * step_deg);
    for (int newton = 0; newton < 3; ++newton)  // onto the shell exactly, as every other step
      pre_q[best] -= (kin.barLength(pre_q, ball, chuck) - at_q) / gradient[best];
    // Where the gradient is too flat for Newton to converge it runs off (once to -47,864 deg):
    // a pre-point stays within a degree of its point, and the pose check then judges the bar.
    constexpr double kMaxBackDeg = 1.0;
    pre_q[best] = std::clamp(pre_q[best], q[best] - kMaxBackDeg, q[best] - step_deg);
  }
  return pre_q;
}

std::vector<JointsDeg> approachStages(const Kinematics& kin, const Eigen::Vector3d& ball,
                                      const Eigen::Vector3d& chuck, const JointsDeg& q,
                                      double step_deg, double max_change_mm,
                                      std::vector<int>& left_out) {
  left_out.clear();
  const double at_q = kin.barLength(q, ball, chuck);
  const auto keeps = [&](const JointsDeg& pre) {
    return std::abs(kin.barLength(pre, ball, chuck) - at_q) <= max_change_mm;
  };
  const JointsDeg single = approachPrePoint(kin, ball, chuck, q, step_deg);
  if (keeps(single)) return {single};
  std::vector<JointsDeg> stages;
  JointsDeg group = q;
  for (int j = 0; j < kJointCount; ++j) {
    JointsDeg alone = q;
    alone[j] -= step_deg;
    if (!keeps(alone)) {
      left_out.push_back(j);
      continue;
    }
    JointsDeg grown = group;
    grown[j] -= step_deg;
    if (keeps(grown)) {
      group = grown;
    } else {
      stages.push_back(group);
      group = alone;
    }
  }
  if (group != q) stages.push_back(group);
  return stages;
}

std::string ShellPlanner::approachProblem(const Connection& c, double radius, const JointsDeg& q,
                                          JointsDeg& pre_q) const {
  pre_q = approachPrePoint(arm_->kinematics(), model().balls_mm[c.ball_index],
                           model().chucks_mm[c.chuck_index], q, cell_.motion.approach_deg);
  return poseProblem(c, radius, pre_q, cell_.motion.via_tolerance_mm);
}

bool ShellPlanner::planApproach(const Connection& c, double radius, const ArmConfig& config,
                                const Node& a, const Node& b, std::vector<PlanStep>& vias,
                                double& worst, std::string& why) const {
  if (cell_.motion.approach_deg <= 0) return planArc(c, radius, config, a, b, 0, vias, worst, why);
  JointsDeg pre_q;
  const std::string problem = approachProblem(c, radius, b.q, pre_q);
  if (!problem.empty()) {
    why = "its approach pre-point: " + problem;
    return false;
  }
  const Eigen::Isometry3d pose = arm_->kinematics().toolPose(pre_q);
  Node pre = nodeFor(c, radius, b.lat_deg, b.lon_deg, pose, pre_q);
  latLonOf(pre.n, pre.lat_deg, pre.lon_deg);  // where its ball is: a step states its place
  if (!planArc(c, radius, config, a, pre, 0, vias, worst, why)) return false;
  vias.push_back({StepKind::kVia, pre_q, pre.lat_deg, pre.lon_deg});
  return planArc(c, radius, config, pre, b, kMaxBisections, vias, worst, why);
}

double ShellPlanner::moveDuration(const JointsDeg& a, const JointsDeg& b) const {
  return (b - a).cwiseAbs().maxCoeff() / cell_.motion.joint_speed_deg_per_s +
         cell_.motion.move_overhead_s;
}

ShellPlanner::BlendProblem ShellPlanner::blendedPathProblem(const Connection& c, double radius,
                                                            const JointsDeg& from,
                                                            const std::vector<JointsDeg>& steps,
                                                            double tolerance_mm) const {
  // Unblended, the path is its segments, each checked on its own (segmentOk, checkPlan).
  const double blend = cell_.motion.blend_deg;
  if (steps.size() < 2 || blend <= 0) return {};
  // Time in degrees of travel: the blend's window is the same at every speed.
  const PathMotion path(from, steps, 1.0, blend);
  // What the blend adds to the segments is smooth at the scale of its window (a corner cut over
  // blend_deg): 16 samples a window find its worst, or a sample every sample_step_mm of the ball
  // (a metre's lever) where that is coarser. The segments themselves are checked finely elsewhere.
  const double step_deg = std::max(blend / 16, cell_.motion.sample_step_mm / 1000.0 * kDegPerRad);
  const double end = path.durationS();
  for (double t = 0; t < end + step_deg; t += step_deg) {
    const double at = std::min(t, end);
    const std::string problem = poseProblem(c, radius, path.at(at), tolerance_mm);
    if (problem.empty()) continue;
    std::size_t nearest = 0;
    // The blended arm is half a blend behind the linear path.
    const double lag = blend / 2;
    for (std::size_t k = 1; k < steps.size(); ++k)
      if (std::abs(path.reachedS(k + 1) + lag - at) <
          std::abs(path.reachedS(nearest + 1) + lag - at))
        nearest = k;
    return {problem, nearest};
  }
  return {};
}

void ShellPlanner::markBlendStops(ShellPlan& shell, std::size_t first_step, JointsDeg from) const {
  const double tolerance = kPlannerToleranceFraction * cell_.motion.via_tolerance_mm;
  for (std::size_t first = first_step; first < shell.steps.size();) {
    const Stretch stretch = stretchFrom(cell_.motion, shell.steps, first);
    const std::size_t last = stretch.last;
    const BlendProblem p =
        blendedPathProblem(shell.connection, shell.radius_mm, from, stretch.joints_deg, tolerance);
    if (p.problem.empty()) {
      from = shell.steps[last].joints_deg;
      first = last + 1;
      continue;
    }
    // Stop at the via nearest the problem (the stretch's last via when that is its end), and
    // check the stretch again up to there.
    shell.steps[first + std::min(p.nearest_step, last - first - 1)].stop = true;
  }
}

void ShellPlanner::finishShell(ShellPlan& shell, std::size_t first_step,
                               const JointsDeg* from) const {
  if (cell_.motion.through_vias)
    markBlendStops(shell, first_step, from ? *from : shell.connect.joints_deg);
  ShellSummary& s = shell.summary;
  s.points = s.vias = 0;
  s.duration_s = 0;
  JointsDeg prev = shell.connect.joints_deg;
  for (const PlanStep& step : shell.steps) {
    (step.kind == StepKind::kPoint ? s.points : s.vias)++;
    s.duration_s += stepDuration(prev, step);
    prev = step.joints_deg;
  }
}

double ShellPlanner::stepDuration(const JointsDeg& from, const PlanStep& step) const {
  const MotionSettings& m = cell_.motion;
  return moveDuration(from, step.joints_deg) - (stopsAt(m, step) ? 0.0 : m.move_overhead_s) +
         (step.kind == StepKind::kPoint ? m.settle_s : 0.0);
}

ShellPlanner::PointTry ShellPlanner::tryPoint(const Connection& c, double radius, double lat_deg,
                                              double lon_deg, const Offset& off,
                                              const ArmConfig& config) const {
  PointTry t;
  t.point = {lat_deg, lon_deg, off, JointsDeg::Zero()};
  const IkSolution ik =
      arm_->solve(policyPose(c, radius, lat_deg, lon_deg, off.yaw_deg, off.pitch_deg, off.roll_deg),
                  config, nullptr);
  if (!ik.ok()) {
    t.problem = std::string("IK: ") + ikStatusName(ik.status);
    return t;
  }
  t.point.joints_deg = ik.joints_deg;
  t.problem = poseProblem(c, radius, ik.joints_deg, cell_.motion.via_tolerance_mm);
  return t;
}

ShellPlanner::GridChoice ShellPlanner::chooseConfig(const Connection& c, double radius,
                                                    const std::vector<double>& lats,
                                                    const std::vector<double>& lons) const {
  const size_t nlat = lats.size(), nlon = lons.size();
  const std::vector<Offset>& offsets = candidateOffsets();
  // The policy's own orientations in every configuration first, then the two best
  // configurations with the other orientations too.
  std::vector<int> configs;
  if (cell_.arm_configuration == "auto") {
    for (int i = 0; i < kArmConfigCount; ++i) configs.push_back(i);
  } else {
    configs.push_back(armConfigIndex(*parseArmConfig(cell_.arm_configuration)));
  }
  std::array<int, kArmConfigCount> nominal_count{};
  std::vector<std::string> nominal_problem(kArmConfigCount * nlat * nlon);
  for (int ci : configs)
    for (size_t i = 0; i < nlat; ++i)
      for (size_t k = 0; k < nlon; ++k) {
        const PointTry t =
            tryPoint(c, radius, lats[i], lons[k], offsets[0], armConfigFromIndex(ci));
        nominal_problem[(ci * nlat + i) * nlon + k] = t.problem;
        if (t.problem.empty()) ++nominal_count[ci];
      }
  std::stable_sort(configs.begin(), configs.end(),
                   [&](int a, int b) { return nominal_count[a] > nominal_count[b]; });
  if (configs.size() > 2) configs.resize(2);
  GridChoice out;
  out.config = configs[0];
  int best_count = -1;
  out.valid.assign(nlat * nlon, 0);
  for (int ci : configs) {
    std::vector<char> ok(nlat * nlon, 0);
    int count = 0;
    for (size_t i = 0; i < nlat; ++i)
      for (size_t k = 0; k < nlon; ++k) {
        if (nominal_problem[(ci * nlat + i) * nlon + k].empty()) {
          ok[i * nlon + k] = 1;
        } else {
          for (size_t o = 1; o < offsets.size() && !ok[i * nlon + k]; ++o)
            ok[i * nlon + k] =
                tryPoint(c, radius, lats[i], lons[k], offsets[o], armConfigFromIndex(ci))
                    .problem.empty();
        }
        count += ok[i * nlon + k];
      }
    if (count > best_count) {
      out.config = ci;
      best_count = count;
      out.valid = ok;
    }
  }
  out.problem.resize(nlat * nlon);
  for (size_t n = 0; n < nlat * nlon; ++n)
    out.problem[n] = nominal_problem[out.config * nlat * nlon + n] + " (and with " +
                     std::to_string(offsets.size() - 1) + " other tool orientations)";
  return out;
}

std::optional<ShellPoint> ShellPlanner::connectPoint(const Connection& c, double radius,
                                                     const ArmConfig& config) const {
  for (const Offset& off : candidateOffsets()) {
    const PointTry t =
        tryPoint(c, radius, cell_.connect_lat_deg, cell_.connect_lon_deg, off, config);
    if (t.problem.empty()) return t.point;
  }
  return std::nullopt;
}

ShellCandidates ShellPlanner::candidatePoints(const Connection& c, double extension_mm,
                                              const GridSettings& grid, int orientations) const {
  const double radius = cell_.bar.nominal_length_mm + extension_mm;
  const std::vector<double> lats = gridLatitudes(grid), lons = gridLongitudes(grid);
  if (lats.empty() || lons.empty()) throw PlanError("cell: grid: the grid is empty");
  const GridChoice choice = chooseConfig(c, radius, lats, lons);
  ShellCandidates out;
  out.config = armConfigFromIndex(choice.config);
  out.connect = connectPoint(c, radius, out.config);
  const std::vector<Offset>& offsets = candidateOffsets();
  for (size_t i = 0; i < lats.size(); ++i)
    for (size_t k = 0; k < lons.size(); ++k) {
      if (!choice.valid[i * lons.size() + k]) continue;
      int found = 0;
      for (size_t o = 0; o < offsets.size() && found < orientations; ++o) {
        const PointTry t = tryPoint(c, radius, lats[i], lons[k], offsets[o], out.config);
        if (!t.problem.empty()) continue;
        JointsDeg pre_q;  // an optimal plan's candidate needs a safe pre-point, or it is dropped
        if (cell_.motion.approach_deg > 0 &&
            !approachProblem(c, radius, t.point.joints_deg, pre_q).empty())
          continue;
        out.points.push_back(t.point);
        ++found;
      }
    }
  return out;
}

ShellPlan ShellPlanner::planShell(const Connection& c, double extension_mm,
                                  int shell_number) const {
  const double radius = cell_.bar.nominal_length_mm + extension_mm;
  std::vector<double> lats = gridLatitudes(cell_.grid);
  const std::vector<double> lons = gridLongitudes(cell_.grid);
  if (lats.empty() || lons.empty()) throw PlanError("cell: grid: the grid is empty");
  // Rings from the one nearest the connect pose.
  if (std::abs(cell_.connect_lat_deg - lats.back()) < std::abs(cell_.connect_lat_deg - lats[0]))
    std::reverse(lats.begin(), lats.end());
  const size_t nlat = lats.size(), nlon = lons.size();
  const std::vector<Offset>& offsets = candidateOffsets();
  const GridChoice choice = chooseConfig(c, radius, lats, lons);
  const std::vector<char>& valid = choice.valid;
  const ArmConfig config = armConfigFromIndex(choice.config);
  const std::optional<ShellPoint> connect = connectPoint(c, radius, config);

  // Travel order: ring by ring; a ring with unreachable points starts after its largest gap so
  // that the path does not cross it; each ring starts near where the previous one ended.
  Eigen::Vector3d here = connect ? unitOnSphere(cell_.connect_lat_deg, cell_.connect_lon_deg)
                                 : Eigen::Vector3d::UnitZ();
  std::vector<std::pair<size_t, size_t>> order;
  for (size_t i = 0; i < nlat; ++i) {
    std::vector<size_t> ring;
    size_t gap_len = 0, gap_end = 0;  // largest circular run of unreachable points
    for (size_t k = 0; k < nlon; ++k) {
      if (valid[i * nlon + k]) continue;
      size_t len = 0;
      while (len < nlon && !valid[i * nlon + (k + len) % nlon]) ++len;
      if (len > gap_len) {
        gap_len = len;
        gap_end = (k + len) % nlon;
      }
    }
    if (gap_len == nlon) {
      for (size_t k = 0; k < nlon; ++k) order.push_back({i, k});  // all dropped
      continue;
    }
    size_t start = gap_end;
    if (gap_len == 0) {  // full ring: start at the point nearest to here
      double best_d = INFINITY;
      for (size_t k = 0; k < nlon; ++k) {
        const double d = (unitOnSphere(lats[i], lons[k]) - here).norm();
        if (d < best_d) {
          best_d = d;
          start = k;
        }
      }
    }
    for (size_t n = 0; n < nlon - gap_len; ++n) ring.push_back((start + n) % nlon);
    // Go the way whose first point is nearer.
    if (gap_len > 0 && (unitOnSphere(lats[i], lons[ring.back()]) - here).norm() <
                           (unitOnSphere(lats[i], lons[ring.front()]) - here).norm())
      std::reverse(ring.begin(), ring.end());
    for (size_t k : ring) order.push_back({i, k});
    for (size_t k = 0; k < nlon; ++k)
      if (std::find(ring.begin(), ring.end(), k) == ring.end()) order.push_back({i, k});
    here = unitOnSphere(lats[i], lons[ring.back()]);
  }

  // Orientation of each point: the safe one nearest to the previous point's.
  std::vector<DroppedPoint> dropped;
  std::vector<ShellPoint> points;
  Offset prev_off = connect ? connect->offset : offsets[0];
  std::vector<size_t> sorted(offsets.size());
  for (const auto& [i, k] : order) {
    if (!valid[i * nlon + k]) {
      dropped.push_back({lats[i], lons[k], choice.problem[i * nlon + k]});
      continue;
    }
    for (size_t o = 0; o < offsets.size(); ++o) sorted[o] = o;
    std::stable_sort(sorted.begin(), sorted.end(), [&](size_t a, size_t b) {
      return offsetDistance(offsets[a], prev_off) + 0.1 * offsetDistance(offsets[a], offsets[0]) <
             offsetDistance(offsets[b], prev_off) + 0.1 * offsetDistance(offsets[b], offsets[0]);
    });
    for (size_t o : sorted) {
      const PointTry t = tryPoint(c, radius, lats[i], lons[k], offsets[o], config);
      if (t.problem.empty()) {
        points.push_back(t.point);
        prev_off = offsets[o];
        break;
      }
    }
  }
  ShellPlan shell = joinPoints(c, extension_mm, shell_number, config, connect, std::move(points));
  shell.dropped.insert(shell.dropped.begin(), dropped.begin(), dropped.end());
  return shell;
}

ShellPlan ShellPlanner::joinPoints(const Connection& c, double extension_mm, int shell_number,
                                   const ArmConfig& config,
                                   const std::optional<ShellPoint>& connect,
                                   std::vector<ShellPoint> chosen) const {
  ShellPlan shell;
  shell.shell = shell_number;
  shell.connection = c;
  shell.extension_mm = extension_mm;
  shell.radius_mm = cell_.bar.nominal_length_mm + extension_mm;
  shell.config = config;
  const double radius = shell.radius_mm;
  const double tol = cell_.motion.via_tolerance_mm;
  if (chosen.empty()) {
    finishShell(shell);
    return shell;
  }
  // Without a safe pose at the connect place, the operator attaches the bar at the first point.
  chosen.insert(chosen.begin(), connect ? *connect : chosen[0]);

  // Joints 4 and 6 turn continuously along the shell; shift the whole sequence by full turns so
  // that it sits inside the limits minus the margin.
  for (int j : {3, 5}) {
    const JointParams& jp = model().joints[j];
    const double period = 360.0 / std::abs(jp.gain);
    double lo = chosen[0].joints_deg[j], hi = lo;
    for (size_t n = 1; n < chosen.size(); ++n) {
      chosen[n].joints_deg[j] =
          chosen[n - 1].joints_deg[j] +
          std::remainder(chosen[n].joints_deg[j] - chosen[n - 1].joints_deg[j], period);
      lo = std::min(lo, chosen[n].joints_deg[j]);
      hi = std::max(hi, chosen[n].joints_deg[j]);
    }
    const double m = cell_.margins.joint_limit_deg;
    const double centre = 0.5 * ((jp.min_deg + m - lo) + (jp.max_deg - m - hi));
    const double shift = period * std::round(centre / period);
    for (ShellPoint& ch : chosen) ch.joints_deg[j] += shift;
  }

  // Vias between consecutive poses.
  auto poseOf = [&](const ShellPoint& ch) {
    return policyPose(c, radius, ch.lat_deg, ch.lon_deg, ch.offset.yaw_deg, ch.offset.pitch_deg,
                      ch.offset.roll_deg);
  };
  // The order of the measurements: every point once, and with motion.revisit_every, after every
  // that many points the one before the last again (the arm has moved on and comes back).
  std::vector<std::pair<size_t, bool>> visits;  // (index in chosen, a revisit)
  const int every = cell_.motion.revisit_every;
  for (size_t n = 0; n < chosen.size(); ++n) {
    visits.push_back({n, false});
    if (every > 0 && n >= 2 && n % static_cast<size_t>(every) == 0) visits.push_back({n - 1, true});
  }
  std::vector<std::optional<Node>> placed(chosen.size());  // each point's first visit
  std::vector<int> visits_of(chosen.size(), 0);            // and how often it was measured
  Node prev;
  // A point measured again: the same joints, reached the same way; a revisit that cannot be
  // joined is left out (it measures the noise or the drift, not the robot: nothing of the grid is
  // lost). Not straight after its last visit (the next point was dropped): the arm must have
  // moved.
  auto revisit = [&](size_t n) {
    const ShellPoint& ch = chosen[n];
    const bool just_measured = !shell.steps.empty() && shell.steps.back().lat_deg == ch.lat_deg &&
                               shell.steps.back().lon_deg == ch.lon_deg;
    if (!placed[n] || just_measured) return;
    std::vector<PlanStep> vias;
    std::string ignored;
    if (!planApproach(c, radius, shell.config, prev, *placed[n], vias,
                      shell.summary.max_deviation_mm, ignored))
      return;
    shell.steps.insert(shell.steps.end(), vias.begin(), vias.end());
    shell.steps.push_back({StepKind::kPoint, placed[n]->q, ch.lat_deg, ch.lon_deg, visits_of[n]++});
    prev = *placed[n];
  };
  // The reference pose (motion.reference_every_min): the shell's first data point, measured again
  // when that much planned robot time has passed since its last measurement, and at the end.
  const double reference_every_s = 60 * cell_.motion.reference_every_min;
  std::optional<size_t> reference;
  std::size_t reference_step = 0;  // index in shell.steps of its last measurement
  // Planned time since then, summed up to steps[timed_to] (each step counted once).
  double since_reference_s = 0;
  std::size_t timed_to = 0;
  auto referenceDue = [&] {
    for (; timed_to + 1 < shell.steps.size(); ++timed_to)
      since_reference_s +=
          stepDuration(shell.steps[timed_to].joints_deg, shell.steps[timed_to + 1]);
    return since_reference_s >= reference_every_s;
  };
  auto startReferenceClock = [&] {
    reference_step = timed_to = shell.steps.size() - 1;
    since_reference_s = 0;
  };
  auto measureReference = [&] {
    const std::size_t before = shell.steps.size();
    revisit(*reference);
    if (shell.steps.size() > before) startReferenceClock();
  };
  for (const auto& [n, is_revisit] : visits) {
    const ShellPoint& ch = chosen[n];
    if (is_revisit) {
      revisit(n);
      continue;
    }
    if (reference && referenceDue()) measureReference();
    const Eigen::Isometry3d pose = poseOf(ch);
    const IkSolution s = arm_->solve(pose, shell.config, &ch.joints_deg);
    const std::string problem = s.ok() ? poseProblem(c, radius, s.joints_deg, tol)
                                       : std::string("IK: ") + ikStatusName(s.status);
    if (n == 0) {
      if (!problem.empty()) {  // cannot happen: the connect pose was checked; keep it safe anyway
        shell.dropped.push_back({ch.lat_deg, ch.lon_deg, "connect pose: " + problem});
        finishShell(shell);
        return shell;
      }
      shell.connect = {StepKind::kPoint, s.joints_deg, ch.lat_deg, ch.lon_deg};
      prev = nodeFor(c, radius, ch.lat_deg, ch.lon_deg, pose, s.joints_deg);
      continue;
    }
    Node node = nodeFor(c, radius, ch.lat_deg, ch.lon_deg, pose, s.joints_deg);
    std::vector<PlanStep> vias;
    std::string why = "after turning joints 4 and 6: " + problem;
    bool joined = problem.empty() && planApproach(c, radius, shell.config, prev, node, vias,
                                                  shell.summary.max_deviation_mm, why);
    if (!joined) {
      // Other orientations at the point, nearest to the previous step's first.
      std::vector<std::pair<double, Offset>> others;
      for (const Offset& off : candidateOffsets()) {
        const Eigen::Quaterniond r(
            policyPose(c, radius, ch.lat_deg, ch.lon_deg, off.yaw_deg, off.pitch_deg, off.roll_deg)
                .linear());
        others.push_back({r.angularDistance(prev.rotation), off});
      }
      std::stable_sort(others.begin(), others.end(),
                       [](const auto& x, const auto& y) { return x.first < y.first; });
      for (size_t o = 0; o < others.size() && o < 8 && !joined; ++o) {
        const Offset& off = others[o].second;
        const Eigen::Isometry3d alt =
            policyPose(c, radius, ch.lat_deg, ch.lon_deg, off.yaw_deg, off.pitch_deg, off.roll_deg);
        const IkSolution t = arm_->solve(alt, shell.config, &prev.q);
        if (!t.ok() || !poseProblem(c, radius, t.joints_deg, tol).empty()) continue;
        node = nodeFor(c, radius, ch.lat_deg, ch.lon_deg, alt, t.joints_deg);
        vias.clear();
        std::string ignored;
        joined = planApproach(c, radius, shell.config, prev, node, vias,
                              shell.summary.max_deviation_mm, ignored);
      }
    }
    if (!joined) {
      shell.dropped.push_back(
          {ch.lat_deg, ch.lon_deg, "no safe path from the previous step: " + why});
      continue;
    }
    shell.steps.insert(shell.steps.end(), vias.begin(), vias.end());
    shell.steps.push_back({StepKind::kPoint, node.q, ch.lat_deg, ch.lon_deg});
    prev = node;
    placed[n] = node;
    visits_of[n] = 1;
    if (!reference && reference_every_s > 0) {
      reference = n;
      startReferenceClock();
    }
  }
  if (reference && reference_step + 1 < shell.steps.size()) measureReference();  // the shell's end
  finishShell(shell);
  return shell;
}

ShellPlan ShellPlanner::replanRemaining(const ShellPlan& old, std::size_t next_step,
                                        const JointsDeg& current) const {
  ShellPlan shell = old;
  next_step = std::min(next_step, old.steps.size());
  shell.steps.resize(next_step);
  shell.summary.max_deviation_mm = 0;
  const double radius = shell.radius_mm;
  const Connection c = shell.connection;
  const Eigen::Isometry3d here = arm_->kinematics().toolPose(current);
  const Eigen::Vector3d ball = here * model().balls_mm[c.ball_index];
  double lat, lon;
  latLonOf((ball - model().chucks_mm[c.chuck_index]).normalized(), lat, lon);
  Node prev = nodeFor(c, radius, lat, lon, here, current);
  prev.slack_mm = std::abs(inspect(c, radius, current).deviation_mm);
  // The old joints' orientation under this model, with the ball put back on the shell, refined
  // from the old joints: cheap, since the models differ little.
  auto carry = [&](const PlanStep& step, IkSolution& s) {
    Eigen::Isometry3d pose = arm_->kinematics().toolPose(step.joints_deg);
    pose.translation() = model().chucks_mm[c.chuck_index] +
                         radius * unitOnSphere(step.lat_deg, step.lon_deg) -
                         pose.linear() * model().balls_mm[c.ball_index];
    s = arm_->refine(pose, shell.config, step.joints_deg);
    return pose;
  };
  std::vector<Node> old_vias;  // the old vias since the last point, carried over
  for (size_t i = next_step; i < old.steps.size(); ++i) {
    const PlanStep& step = old.steps[i];
    IkSolution s;
    const Eigen::Isometry3d pose = carry(step, s);
    if (step.kind == StepKind::kVia) {
      if (s.ok() && poseProblem(c, radius, s.joints_deg, cell_.motion.via_tolerance_mm).empty())
        old_vias.push_back(nodeFor(c, radius, step.lat_deg, step.lon_deg, pose, s.joints_deg));
      continue;
    }
    if (!s.ok()) s = arm_->solve(pose, shell.config, &prev.q);
    std::string why = s.ok() ? poseProblem(c, radius, s.joints_deg, cell_.motion.via_tolerance_mm)
                             : std::string("IK: ") + ikStatusName(s.status);
    if (!why.empty()) {
      shell.dropped.push_back({step.lat_deg, step.lon_deg, why});
      old_vias.clear();
      continue;
    }
    // The old approach pre-point is planned afresh from the new point.
    if (cell_.motion.approach_deg > 0 && !old_vias.empty()) old_vias.pop_back();
    const Node node = nodeFor(c, radius, step.lat_deg, step.lon_deg, pose, s.joints_deg);
    // Through the carried-over vias first (bisecting where a move needs more), else afresh.
    std::vector<PlanStep> vias;
    bool joined = true;
    const Node* from = &prev;
    for (const Node& v : old_vias) {
      std::string ignored;
      if (!planArc(c, radius, shell.config, *from, v, 0, vias, shell.summary.max_deviation_mm,
                   ignored)) {
        joined = false;
        break;
      }
      vias.push_back({StepKind::kVia, v.q, v.lat_deg, v.lon_deg});
      from = &v;
    }
    if (joined)
      joined = planApproach(c, radius, shell.config, *from, node, vias,
                            shell.summary.max_deviation_mm, why);
    if (!joined) {
      vias.clear();
      joined = planApproach(c, radius, shell.config, prev, node, vias,
                            shell.summary.max_deviation_mm, why);
    }
    old_vias.clear();
    if (!joined) {
      shell.dropped.push_back(
          {step.lat_deg, step.lon_deg, "no safe path from the previous step: " + why});
      continue;
    }
    shell.steps.insert(shell.steps.end(), vias.begin(), vias.end());
    shell.steps.push_back({StepKind::kPoint, s.joints_deg, step.lat_deg, step.lon_deg, step.visit});
    prev = node;
  }
  // The arm goes on from `current`, not from the step before next_step: its first blended
  // stretch is checked from there, and what it has done is not checked again.
  finishShell(shell, next_step, &current);
  return shell;
}

const char* planPurposeName(PlanPurpose purpose) {
  switch (purpose) {
    case PlanPurpose::kCheck:
      return "check";
    case PlanPurpose::kIsoTest:
      return "iso9283";
    case PlanPurpose::kCalibration:
      break;
  }
  return "calibration";
}

std::optional<PlanPurpose> parsePlanPurpose(const std::string& name) {
  if (name == "calibration") return PlanPurpose::kCalibration;
  if (name == "check") return PlanPurpose::kCheck;
  if (name == "iso9283") return PlanPurpose::kIsoTest;
  return std::nullopt;
}

void summarizePlan(Plan& plan) {
  PlanSummary& s = plan.summary;
  s.shells = static_cast<int>(plan.shells.size());
  s.points = s.vias = s.dropped = 0;
  s.duration_s = s.max_deviation_mm = 0;
  s.predicted_deflection_mm = -1;
  s.predicted_change_mm = -1;
  for (const ShellPlan& shell : plan.shells) {
    s.points += shell.summary.points;
    s.vias += shell.summary.vias;
    s.dropped += static_cast<int>(shell.dropped.size());
    s.duration_s += shell.summary.duration_s;
    s.max_deviation_mm = std::max(s.max_deviation_mm, shell.summary.max_deviation_mm);
    s.predicted_deflection_mm =
        std::max(s.predicted_deflection_mm, shell.summary.predicted_deflection_mm);
    s.predicted_change_mm = std::max(s.predicted_change_mm, shell.summary.predicted_change_mm);
  }
  s.swap_time_s = s.shells * plan.cell.motion.swap_s;
  s.cell_time_s = s.duration_s + s.swap_time_s;
}

CellTimeParts cellTimeParts(const Plan& plan) {
  const MotionSettings& m = plan.cell.motion;
  CellTimeParts parts;
  for (const ShellPlan& shell : plan.shells) {
    JointsDeg prev = shell.connect.joints_deg;
    for (const PlanStep& step : shell.steps) {
      parts.motion_s += (step.joints_deg - prev).cwiseAbs().maxCoeff() / m.joint_speed_deg_per_s;
      if (stopsAt(m, step)) {
        parts.stopping_s += m.move_overhead_s;
        ++parts.stops;
      }
      if (step.kind == StepKind::kPoint) {
        ++parts.points;
        parts.dwell_s += m.settle_s;
      }
      prev = step.joints_deg;
    }
  }
  parts.swap_s = static_cast<double>(plan.shells.size()) * m.swap_s;
  return parts;
}

Plan planCell(const Model& model, const CellConfig& cell) {
  const ShellPlanner planner(model, cell);
  Plan plan;
  plan.model_name = model.name;
  plan.cell = cell;
  struct Job {
    Connection connection;
    double extension_mm;
  };
  std::vector<Job> jobs;
  for (double extension : cell.bar.extension_lengths_mm)
    for (const Connection& c : cell.connections) jobs.push_back({c, extension});
  // Shells are independent: plan them on a few threads.
  plan.shells.resize(jobs.size());
  detail::parallelFor(jobs.size(), [&](size_t i) {
    plan.shells[i] =
        planner.planShell(jobs[i].connection, jobs[i].extension_mm, static_cast<int>(i) + 1);
  });
  for (const ShellPlan& shell : plan.shells)
    if (shell.summary.points == 0) {
      std::string msg =
          "shell " + std::to_string(shell.shell) + " (" + connectionName(shell.connection) +
          fmt(", radius %.1f mm): no grid point can be reached safely", shell.radius_mm);
      if (!shell.dropped.empty())
        msg += fmt(" (e.g. lat %.1f lon %.1f deg: ", shell.dropped[0].lat_deg,
                   shell.dropped[0].lon_deg) +
               shell.dropped[0].reason + ")";
      throw PlanError(msg);
    }
  summarizePlan(plan);
  return plan;
}

std::vector<Sample> planSamples(const Model& model, const Plan& plan) {
  const Kinematics kin(model);
  std::vector<Sample> out;
  for (const ShellPlan& shell : plan.shells)
    for (const PlanStep& step : shell.steps) {
      if (step.kind != StepKind::kPoint) continue;
      const Connection& c = shell.connection;
      out.push_back(makeSample(shell.shell, c, shell.extension_mm, step.lat_deg, step.lon_deg,
                               step.joints_deg,
                               kin.barLength(step.joints_deg, model.balls_mm[c.ball_index],
                                             model.chucks_mm[c.chuck_index])));
    }
  return out;
}

PlanIdentifiability planIdentifiability(const Model& model, const Plan& plan, double extension_mm) {
  std::vector<Sample> samples = planSamples(model, plan);
  if (extension_mm >= 0)
    std::erase_if(samples,
                  [&](const Sample& s) { return std::abs(s.extension_mm - extension_mm) > 1e-9; });
  PlanIdentifiability out;
  out.points = static_cast<int>(samples.size());
  if (samples.empty()) return out;
  Eigen::VectorXd residuals;
  Eigen::MatrixXd jacobian;
  evaluateProblem(model, toParams(model), samples, residuals, &jacobian);
  const Identifiability id = analyzeIdentifiability(jacobian);
  out.rank = id.rank;
  out.expected_rank = id.expected;
  out.condition_number = id.rank > 0 ? 1.0 / id.singular_values[id.rank - 1] : 0;
  return out;
}

void summarizeIdentifiability(const Model& model, Plan& plan) {
  const PlanIdentifiability id = planIdentifiability(model, plan);
  plan.summary.rank = id.rank;
  plan.summary.expected_rank = id.expected_rank;
  plan.summary.condition_number = id.condition_number;
}

void predictDeflections(const Model& nominal, const std::vector<Model>& truths, Plan& plan) {
  (void)nominal;
  for (ShellPlan& shell : plan.shells) {
    double worst = 0, change = 0;
    for (const Model& truth : truths) {
      const Kinematics kin(truth);
      const Eigen::Vector3d ball = truth.balls_mm[shell.connection.ball_index];
      const Eigen::Vector3d chuck = truth.chucks_mm[shell.connection.chuck_index];
      const double at_connect =
          kin.barLength(shell.connect.joints_deg, ball, chuck) - shell.radius_mm;
      worst = std::max(worst, std::abs(at_connect));
      for (const PlanStep& step : shell.steps) {
        const double e = kin.barLength(step.joints_deg, ball, chuck) - shell.radius_mm;
        worst = std::max(worst, std::abs(e));
        change = std::max(change, std::abs(e - at_connect));
      }
    }
    shell.summary.predicted_deflection_mm =
        truths.empty() ? -1 : worst + shell.summary.max_deviation_mm;
    shell.summary.predicted_change_mm =
        truths.empty() ? -1 : change + shell.summary.max_deviation_mm;
  }
  summarizePlan(plan);
}

}  // namespace robocal
