#include <robocal/compensation/accuracy.hpp>

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/units.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>

namespace robocal {

namespace {

// The work volume's draws that compensate with status ok, with their targets.
std::vector<std::pair<Eigen::Isometry3d, CompensatedTarget>> drawWorkVolume(
    const WorkVolume& work, const Compensator& compensator) {
  std::mt19937_64 rng(static_cast<std::uint64_t>(work.seed));
  auto uniform = [&](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  std::vector<std::pair<Eigen::Isometry3d, CompensatedTarget>> poses;
  const long max_draws = 50L * work.poses;
  for (long draw = 0; draw < max_draws && static_cast<int>(poses.size()) < work.poses; ++draw) {
    const Eigen::Isometry3d pose =
        poseFromXyzZyx(uniform(work.box_min_mm[0], work.box_max_mm[0]),
                       uniform(work.box_min_mm[1], work.box_max_mm[1]),
                       uniform(work.box_min_mm[2], work.box_max_mm[2]),
                       uniform(work.rz_range_deg[0], work.rz_range_deg[1]),
                       uniform(work.ry_range_deg[0], work.ry_range_deg[1]),
                       uniform(work.rx_range_deg[0], work.rx_range_deg[1]));
    // Reachable by the nominal model: the controller could be commanded there at all.
    const CompensatedTarget t = compensator.forPose(pose);
    if (t.solved()) poses.push_back({pose, t});
  }
  if (static_cast<int>(poses.size()) < work.poses)
    throw std::invalid_argument(
        "work_volume: only " + std::to_string(poses.size()) + " of " + std::to_string(max_draws) +
        " poses drawn from the box and angle ranges are reachable (wanted " +
        std::to_string(work.poses) + "): move the box or the angle ranges into the arm's reach");
  return poses;
}

// Compensates targets 0..count-1 (`target_at`) and gathers the statistics over those solved.
AccuracyReport assess(const Compensator& compensator, std::size_t count,
                      const std::function<CompensatedTarget(std::size_t)>& target_at,
                      const TrueRobot* truth);

}  // namespace

std::vector<Eigen::Isometry3d> workVolumePoses(const WorkVolume& work,
                                               const Compensator& compensator) {
  std::vector<Eigen::Isometry3d> out;
  for (const auto& [pose, target] : drawWorkVolume(work, compensator)) out.push_back(pose);
  return out;
}

std::vector<JointsDeg> workVolumeJoints(const WorkVolume& work, const Compensator& compensator) {
  std::vector<JointsDeg> out;
  for (const auto& [pose, target] : drawWorkVolume(work, compensator))
    out.push_back(target.joints_deg);
  return out;
}

ErrorStats errorStats(std::vector<double> values) {
  ErrorStats s;
  s.count = values.size();
  if (values.empty()) return s;
  double sum_sq = 0;
  for (double v : values) sum_sq += v * v;
  s.rms = std::sqrt(sum_sq / static_cast<double>(values.size()));
  std::sort(values.begin(), values.end());
  s.max = values.back();
  const size_t rank = static_cast<size_t>(std::ceil(0.95 * static_cast<double>(values.size())));
  s.p95 = values[std::max<size_t>(rank, 1) - 1];
  return s;
}

AccuracyReport assessAccuracy(const Compensator& compensator,
                              const std::vector<Eigen::Isometry3d>& targets, const TrueRobot* truth,
                              const std::vector<std::optional<ArmConfig>>& configs) {
  if (!configs.empty() && configs.size() != targets.size())
    throw std::invalid_argument("assessAccuracy: one configuration a target, or none");
  return assess(
      compensator, targets.size(),
      [&](std::size_t i) {
        return compensator.forPose(targets[i], configs.empty() ? std::nullopt : configs[i]);
      },
      truth);
}

AccuracyReport assessAccuracyAtJoints(const Compensator& compensator,
                                      const std::vector<JointsDeg>& nominal_joints_deg,
                                      const TrueRobot* truth) {
  return assess(
      compensator, nominal_joints_deg.size(),
      [&](std::size_t i) { return compensator.forNominalJoints(nominal_joints_deg[i]); }, truth);
}

namespace {

// The side each joint comes from into target i of a program without pre-points: either, the same
// for every run (a fixed hash of the index, each joint its own bits).
Approach eitherSide(std::size_t i) {
  std::uint64_t h = (i + 1) * 0x9E3779B97F4A7C15ull;
  h ^= h >> 31;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 29;
  Approach side{};
  for (int j = 0; j < kJointCount; ++j) side[j] = (h >> (7 * j + 3)) & 1 ? 1 : -1;
  return side;
}

AccuracyReport assess(const Compensator& compensator, std::size_t count,
                      const std::function<CompensatedTarget(std::size_t)>& target_at,
                      const TrueRobot* truth) {
  AccuracyReport r;
  r.requested = count;
  r.has_truth = truth != nullptr;
  std::optional<Kinematics> true_kin;
  if (truth) true_kin.emplace(truth->modelAt(1e6));  // warm
  // Where the true robot's tool is at commanded readings reached with `approach`.
  const auto true_tool = [&](const JointsDeg& q, const Approach& approach) {
    return true_kin->toolPose(truth->effectiveReadings(q, approach));
  };
  const Eigen::Isometry3d& tool = compensator.options().tool;
  std::vector<double> pred_pos, pred_ori, nom_pos, nom_ori, comp_pos, comp_ori, model_pos,
      model_ori;
  for (std::size_t i = 0; i < count; ++i) {
    PoseAccuracy a;
    a.target = target_at(i);
    const Eigen::Isometry3d& pose = a.target.target;
    if (true_kin) {
      // Each target is reached as the output commands it: up in every joint from its pre-point
      // when it has one; without, from whichever side the program came (a plain program, the
      // nominal joints included, has no pre-points).
      const Approach program_side = eitherSide(i);
      const Eigen::Isometry3d at_nominal =
          true_tool(a.target.nominal_joints_deg, program_side) * tool;
      const Eigen::Isometry3d at_compensated =
          true_tool(a.target.joints_deg,
                    a.target.hasApproach() ? kPositiveApproach : program_side) *
          tool;
      a.nominal_commanded = poseDifference(at_nominal, pose);
      a.compensated_commanded = poseDifference(at_compensated, pose);
      a.calibrated_model =
          poseDifference(at_compensated, compensator.calibratedToolPose(a.target.joints_deg));
    }
    if (a.target.ok()) ++r.ok;
    if (a.target.solved()) {
      ++r.solved;
      pred_pos.push_back(a.target.predicted_position_error_mm);
      pred_ori.push_back(a.target.predicted_orientation_error_deg);
      nom_pos.push_back(a.nominal_commanded.position_mm);
      nom_ori.push_back(a.nominal_commanded.angle_deg);
      comp_pos.push_back(a.compensated_commanded.position_mm);
      comp_ori.push_back(a.compensated_commanded.angle_deg);
      model_pos.push_back(a.calibrated_model.position_mm);
      model_ori.push_back(a.calibrated_model.angle_deg);
    }
    r.poses.push_back(a);
  }
  if (compensator.calibrated().covariance) {
    r.predicted_position_mm = errorStats(pred_pos);
    r.predicted_orientation_deg = errorStats(pred_ori);
  }
  if (truth) {
    r.nominal_position_mm = errorStats(nom_pos);
    r.nominal_orientation_deg = errorStats(nom_ori);
    r.compensated_position_mm = errorStats(comp_pos);
    r.compensated_orientation_deg = errorStats(comp_ori);
    r.calibrated_model_position_mm = errorStats(model_pos);
    r.calibrated_model_orientation_deg = errorStats(model_ori);
  }
  return r;
}

}  // namespace

}  // namespace robocal
