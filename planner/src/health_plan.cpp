#include <robocal/planner/health_plan.hpp>

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/units.hpp>
#include <robocal/planner/design.hpp>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>

namespace robocal {

double healthCheckExtension(const BarSettings& calibration) {
  std::vector<double> e = calibration.extension_lengths_mm;
  std::sort(e.begin(), e.end());
  double best_gap = 0, midpoint = 0;
  for (size_t i = 1; i < e.size(); ++i)
    if (e[i] - e[i - 1] > best_gap + 1e-9) {
      best_gap = e[i] - e[i - 1];
      midpoint = 0.5 * (e[i] + e[i - 1]);
    }
  if (best_gap > 0) return midpoint;
  return (e.empty() ? 0.0 : e.front()) + 0.5 * calibration.nominal_length_mm;
}

std::vector<Connection> healthCheckConnections(const std::vector<Connection>& calibration) {
  // Chuck of ball 1, 2, 3 (0-based) for each matching, in the order of preference: the two
  // "rotations" first (no ball on the chuck of its own number), then the diagonal and the three
  // matchings that swap two chucks.
  static constexpr std::array<std::array<int, 3>, 6> kMatchings = {
      {{1, 2, 0}, {2, 0, 1}, {0, 1, 2}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}}};
  for (const auto& chucks : kMatchings) {
    std::vector<Connection> out;
    for (int b = 0; b < kBallCount; ++b) {
      const Connection c{b, chucks[b]};
      if (std::find(calibration.begin(), calibration.end(), c) != calibration.end())
        out.push_back(c);
    }
    if (out.size() == kBallCount) return out;
  }
  throw PlanError(
      "the health check needs three connections that use every ball and every chuck, "
      "and the cell's connections (" +
      connectionList(calibration) + ") hold none");
}

CellConfig healthCheckCell(const CellConfig& calibration) {
  CellConfig cell = calibration;
  cell.connections = healthCheckConnections(calibration.connections);
  cell.connections.resize(kHealthCheckShells);
  cell.bar.extension_lengths_mm = {healthCheckExtension(calibration.bar)};
  GridSettings grid = kHealthCheckCandidateGrid;
  grid.longitude_first_deg = calibration.grid.longitude_first_deg;
  cell.grid = grid;
  if (!calibration.name.empty()) cell.name = calibration.name + ", health check";
  return cell;
}

namespace {

// The change each parameter must be seen at, over the noise (ParamVector units per mm); 0 for
// the parameters the check is not designed for (link angles, gains).
Eigen::Matrix<double, kParamCount, 1> detectionTargets() {
  constexpr double kNoiseMm = 0.084;  // the paper's; the design does not depend on its size
  Eigen::Matrix<double, kParamCount, 1> d = Eigen::Matrix<double, kParamCount, 1>::Zero();
  for (int link = 0; link < kLinkCount; ++link)
    for (int axis = 0; axis < 3; ++axis)
      d[linkParamIndex(link) + axis] = kHealthCheckTranslationMm / kNoiseMm;
  for (int joint = 0; joint < kJointCount; ++joint)
    d[jointParamIndex(joint)] =
        degToRad(joint < 3 ? kHealthCheckJoint13Deg : kHealthCheckJoint46Deg) / kNoiseMm;
  return d;
}

}  // namespace

Plan planHealthCheck(const Model& model, const CellConfig& calibration) {
  const CellConfig cell = healthCheckCell(calibration);
  const ShellPlanner planner(model, cell);
  const Kinematics kin(model);
  const Eigen::Matrix<double, kParamCount, 1> targets = detectionTargets();
  const double extension_mm = cell.bar.extension_lengths_mm.front();

  // Each candidate's contribution to every parameter's noncentrality, (dL/dp_k d_k / sigma)^2.
  struct Pool {
    ShellCandidates candidates;
    Eigen::MatrixXd signal;  // kParamCount x candidates
  };
  std::vector<Pool> pools(cell.connections.size());
  for (size_t s = 0; s < pools.size(); ++s) {
    const Connection& c = cell.connections[s];
    Pool& pool = pools[s];
    pool.candidates = planner.candidatePoints(c, extension_mm, cell.grid, kHealthCheckOrientations);
    const size_t n = pool.candidates.points.size();
    if (n == 0)
      throw PlanError("the health check's shell " + connectionName(c) +
                      " has no point that can be reached safely");
    pool.signal.resize(kParamCount, static_cast<Eigen::Index>(n));
    ParamRow gradient;
    for (size_t i = 0; i < n; ++i) {
      kin.barLengthGradient(pool.candidates.points[i].joints_deg, model.balls_mm[c.ball_index],
                            model.chucks_mm[c.chuck_index], gradient);
      pool.signal.col(static_cast<Eigen::Index>(i)) =
          (gradient.transpose().array() * targets.array()).square().matrix();
    }
  }

  // Greedy: the points that raise sum_k log(1 + S_k) most per second of robot time (the dwell
  // and the move from the nearest point already chosen on the shell, from the connect pose at
  // first, that move's time weighted by `travel_weight`), the shells in turn so that each gets
  // its share.
  const MotionSettings& motion = cell.motion;
  auto travel_s = [&](const JointsDeg& a, const JointsDeg& b) {
    return (b - a).cwiseAbs().maxCoeff() / motion.joint_speed_deg_per_s;
  };
  const int per_shell = kHealthCheckPoints / static_cast<int>(pools.size());
  auto pick = [&](double travel_weight) {
    std::vector<std::vector<char>> chosen(pools.size());
    std::vector<std::vector<double>> nearest_s(pools.size());
    for (size_t s = 0; s < pools.size(); ++s) {
      const ShellCandidates& c = pools[s].candidates;
      chosen[s].assign(c.points.size(), 0);
      for (const ShellPoint& p : c.points)
        nearest_s[s].push_back(c.connect ? travel_s(c.connect->joints_deg, p.joints_deg) : 0.0);
    }
    Eigen::Matrix<double, kParamCount, 1> noncentrality =
        Eigen::Matrix<double, kParamCount, 1>::Zero();
    for (int round = 0; round < per_shell; ++round)
      for (size_t s = 0; s < pools.size(); ++s) {
        const Pool& pool = pools[s];
        const Eigen::ArrayXd base = (1.0 + noncentrality.array()).log();
        Eigen::Index best = -1;
        double best_gain = -1;
        for (Eigen::Index i = 0; i < pool.signal.cols(); ++i) {
          const size_t k = static_cast<size_t>(i);
          if (chosen[s][k]) continue;
          const double gain =
              ((1.0 + noncentrality.array() + pool.signal.col(i).array()).log() - base).sum() /
              (motion.settle_s + motion.move_overhead_s + travel_weight * nearest_s[s][k]);
          if (gain > best_gain) {
            best_gain = gain;
            best = i;
          }
        }
        if (best < 0) continue;  // the shell has fewer candidates than its share
        chosen[s][static_cast<size_t>(best)] = 1;
        noncentrality += pool.signal.col(best);
        const JointsDeg& q = pool.candidates.points[static_cast<size_t>(best)].joints_deg;
        for (size_t i = 0; i < pool.candidates.points.size(); ++i)
          nearest_s[s][i] =
              std::min(nearest_s[s][i], travel_s(q, pool.candidates.points[i].joints_deg));
      }
    return chosen;
  };
  // The pick's travel is a guess (it does not see the vias a move needs, which the join adds):
  // a few weights of it, and the plan with the most points in the least robot time kept. On
  // perturbed models a single weight landed on 2.5 or 3.1 minutes (docs/health-check.md).
  Plan plan;
  for (double travel_weight : {1.0, 1.5, 2.0, 3.0}) {
    const std::vector<std::vector<char>> chosen = pick(travel_weight);
    std::vector<ShellChoice> choices;
    for (size_t s = 0; s < pools.size(); ++s)
      choices.push_back({cell.connections[s], extension_mm, &pools[s].candidates, chosen[s]});
    Plan candidate = joinChosenPoints(model, planner, choices);
    if (plan.shells.empty() || candidate.summary.points > plan.summary.points ||
        (candidate.summary.points == plan.summary.points &&
         candidate.summary.duration_s < plan.summary.duration_s))
      plan = std::move(candidate);
  }
  plan.purpose = PlanPurpose::kCheck;
  summarizeIdentifiability(model, plan);
  return plan;
}

}  // namespace robocal
