#include <robocal/planner/health_plan.hpp>

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
  cell.bar.extension_lengths_mm = {healthCheckExtension(calibration.bar)};
  cell.grid.latitude_first_deg = kHealthCheckLatitudeFirstDeg;
  cell.grid.latitude_last_deg = kHealthCheckLatitudeLastDeg;
  cell.grid.latitude_step_deg = kHealthCheckLatitudeStepDeg;
  cell.grid.longitude_step_deg = kHealthCheckLongitudeStepDeg;
  if (!calibration.name.empty()) cell.name = calibration.name + ", health check";
  return cell;
}

Plan planHealthCheck(const Model& model, const CellConfig& calibration) {
  Plan plan = planCell(model, healthCheckCell(calibration));
  plan.purpose = PlanPurpose::kCheck;
  summarizeIdentifiability(model, plan);
  return plan;
}

}  // namespace robocal
