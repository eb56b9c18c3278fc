// Arm::solveFromSeeds: the numeric inverse kinematics of any six-revolute arm (arm.hpp).
#include <robocal/robot/arm.hpp>

#include <algorithm>
#include <cmath>
#include <random>

namespace robocal {

std::vector<const Arm::Seed*> Arm::nearestSeeds(const Eigen::Isometry3d& target,
                                                const ArmConfig& config, int count) const {
  std::call_once(seeds_built_, [this] {
    std::mt19937_64 rng(20261206);  // fixed: the same seeds, the same answers, on every run
    for (int i = 0; i < kSeedCount; ++i) {
      Seed seed;
      for (int j = 0; j < kJointCount; ++j) {
        const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;  // [0, 1)
        const JointParams& jp = model_.joints[j];
        seed.q[j] = jp.min_deg + u * (jp.max_deg - jp.min_deg);
      }
      const Eigen::Isometry3d pose = kin_.toolPose(seed.q);
      if (!pose.matrix().allFinite()) continue;
      seed.position_mm = pose.translation();
      seed.rotation = Eigen::Quaterniond(pose.linear());
      seeds_[armConfigIndex(configOf(seed.q))].push_back(seed);
    }
  });
  const std::vector<Seed>& table = seeds_[armConfigIndex(config)];
  const Eigen::Quaterniond rotation(target.linear());
  const double scale = refine_options_.orientation_scale_mm;
  std::vector<std::pair<double, const Seed*>> ranked;
  ranked.reserve(table.size());
  for (const Seed& s : table) {
    const double angle = 2.0 * std::acos(std::min(1.0, std::abs(s.rotation.dot(rotation))));
    ranked.emplace_back((s.position_mm - target.translation()).norm() + scale * angle, &s);
  }
  const auto end = ranked.begin() + std::min<std::ptrdiff_t>(count, std::ssize(ranked));
  std::partial_sort(ranked.begin(), end, ranked.end(),
                    [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<const Seed*> out;
  for (auto it = ranked.begin(); it != end; ++it) out.push_back(it->second);
  return out;
}

IkSolution Arm::solveFromSeeds(const Eigen::Isometry3d& target, const ArmConfig& config,
                               const JointsDeg* near) const {
  IkSolution s;
  s.config = config;
  if (!target.matrix().allFinite()) return s;  // kUnreachable, zero joints
  Descent best;
  auto attempt = [&](const JointsDeg& seed) {
    const Descent d = descend(target, &config, seed);
    if (found(d, config) || (!found(best, config) && d.cost < best.cost)) best = d;
    return found(d, config);
  };
  bool solved = near && near->allFinite() && attempt(*near);
  if (!solved) {
    for (const Seed* seed : nearestSeeds(target, config, kSeedsTried)) {
      if (attempt(seed->q)) {
        solved = true;
        break;
      }
    }
  }
  s.joints_deg = best.q.allFinite() ? best.q : JointsDeg::Zero();
  measureError(s, target);
  if (solved) {
    judgeConverged(s, target, near);
    return s;
  }
  s.status = IkStatus::kUnreachable;
  for (int i = 0; i < kArmConfigCount && s.status == IkStatus::kUnreachable; ++i)
    for (const Seed* seed : nearestSeeds(target, armConfigFromIndex(i), 2))
      if (descend(target, nullptr, seed->q).converged) s.status = IkStatus::kNoConvergence;
  return s;
}

}  // namespace robocal
