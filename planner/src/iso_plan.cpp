#include <robocal/kinematics/kinematics.hpp>
#include <robocal/planner/iso_plan.hpp>

#include <cmath>
#include <limits>

namespace robocal {
namespace {

// The candidate nearest (lat, lon) in degrees of the shell (longitude wrapped), not in `taken`.
std::size_t nearestCandidate(const std::vector<ShellPoint>& points, double lat_deg, double lon_deg,
                             const std::vector<std::size_t>& taken) {
  std::size_t best = points.size();
  double best_d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < points.size(); ++i) {
    bool used = false;
    for (std::size_t t : taken) used |= t == i;
    const double dlat = points[i].lat_deg - lat_deg;
    const double dlon = std::remainder(points[i].lon_deg - lon_deg, 360.0);
    const double d = dlat * dlat + dlon * dlon;
    if (!used && d < best_d) best_d = d, best = i;
  }
  return best;
}

}  // namespace

Plan planIsoTest(const Model& model, const CellConfig& calibration, const IsoTestSettings& t) {
  if (t.cycles < 2 || t.cycles > 1000)
    throw PlanError("iso: cycles must be from 2 to 1000 (the standard's 30)");
  if (t.warmup_cycles < 0 || t.warmup_cycles > 1000)
    throw PlanError("iso: warmup_cycles must be from 0 to 1000");
  if (!(t.spread_deg >= 2 && t.spread_deg <= 40))
    throw PlanError("iso: spread_deg must be from 2 to 40");
  if (calibration.connections.empty() || calibration.bar.extension_lengths_mm.empty())
    throw PlanError("iso: the cell has no connection or no extension to test with");
  CellConfig cell = calibration;
  cell.motion.revisit_every = 0;
  cell.motion.reference_every_min = 0;
  cell.connections = {calibration.connections.front()};
  cell.bar.extension_lengths_mm = {calibration.bar.extension_lengths_mm.front()};
  if (!calibration.name.empty()) cell.name = calibration.name + ", ISO 9283-style test";
  const ShellPlanner planner(model, cell);
  const Connection c = cell.connections.front();
  const double extension = cell.bar.extension_lengths_mm.front();

  // Candidates on a 5-degree grid over the calibration's latitudes, one orientation each.
  GridSettings grid = cell.grid;
  grid.latitude_step_deg = grid.longitude_step_deg = 5;
  const ShellCandidates candidates = planner.candidatePoints(c, extension, grid, 1);
  const std::vector<ShellPoint>& points = candidates.points;
  if (points.size() < kIsoPoseCount)
    throw PlanError("iso: the shell of " + connectionName(c) + " holds " +
                    std::to_string(points.size()) + " safe points, the test needs " +
                    std::to_string(kIsoPoseCount));

  const WorkVolume& w = cell.work_volume;
  const Eigen::Vector3d centre(0.5 * (w.box_min_mm[0] + w.box_max_mm[0]),
                               0.5 * (w.box_min_mm[1] + w.box_max_mm[1]),
                               0.5 * (w.box_min_mm[2] + w.box_max_mm[2]));
  const Kinematics kin(model);
  std::size_t p1 = 0;
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double d =
        (kin.ballPosition(points[i].joints_deg, model.balls_mm[c.ball_index]) - centre).norm();
    if (d < nearest) nearest = d, p1 = i;
  }
  std::vector<std::size_t> chosen = {p1};
  const double s = t.spread_deg;
  for (const auto& [dlat, dlon] : {std::pair{s, s}, {s, -s}, {-s, -s}, {-s, s}})
    chosen.push_back(
        nearestCandidate(points, points[p1].lat_deg + dlat, points[p1].lon_deg + dlon, chosen));

  std::vector<ShellPoint> cycle_points;
  for (int k = 0; k < t.warmup_cycles + t.cycles; ++k)
    for (std::size_t i : chosen) cycle_points.push_back(points[i]);
  ShellPlan shell =
      planner.joinPoints(c, extension, 1, candidates.config, std::nullopt, std::move(cycle_points));
  if (!shell.dropped.empty())
    throw PlanError("iso: a test pose cannot be reached the same way every cycle: lat " +
                    std::to_string(shell.dropped.front().lat_deg) + " lon " +
                    std::to_string(shell.dropped.front().lon_deg) + ": " +
                    shell.dropped.front().reason);
  // Each pose's measurements numbered 0, 1, 2, ... (the cycles, warm-up first).
  std::vector<std::pair<std::pair<double, double>, int>> seen;
  for (PlanStep& step : shell.steps) {
    if (step.kind != StepKind::kPoint) continue;
    int* count = nullptr;
    for (auto& [place, n] : seen)
      if (place == std::pair{step.lat_deg, step.lon_deg}) count = &n;
    if (!count) count = &seen.emplace_back(std::pair{step.lat_deg, step.lon_deg}, 0).second;
    step.visit = (*count)++;
  }
  Plan plan;
  plan.model_name = model.name;
  plan.purpose = PlanPurpose::kIsoTest;
  plan.iso = t;
  plan.cell = cell;
  plan.shells.push_back(std::move(shell));
  summarizePlan(plan);
  return plan;
}

}  // namespace robocal
