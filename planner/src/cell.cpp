#include <robocal/planner/cell.hpp>
#include <robocal/robot/arm.hpp>

#include <cmath>
#include <stdexcept>

namespace robocal {
namespace {

[[noreturn]] void bad(const std::string& key, const std::string& problem) {
  throw std::invalid_argument(key + ": " + problem);
}

void positive(const std::string& key, double v) {
  if (!(v > 0) || !std::isfinite(v)) bad(key, "must be positive, got " + std::to_string(v));
}

void nonNegative(const std::string& key, double v) {
  if (!(v >= 0) || !std::isfinite(v)) bad(key, "must not be negative, got " + std::to_string(v));
}

void inRange(const std::string& key, double v, double lo, double hi) {
  if (!(v >= lo && v <= hi))
    bad(key, "must be within " + std::to_string(lo) + " .. " + std::to_string(hi) + ", got " +
                 std::to_string(v));
}

}  // namespace

std::vector<double> gridLatitudes(const GridSettings& g) {
  std::vector<double> out;
  if (!(g.latitude_step_deg > 0)) return out;
  for (double lat = g.latitude_first_deg; lat <= g.latitude_last_deg + 1e-9;
       lat += g.latitude_step_deg)
    out.push_back(lat);
  return out;
}

std::vector<double> gridLongitudes(const GridSettings& g) {
  std::vector<double> out;
  if (!(g.longitude_step_deg > 0)) return out;
  const int n = static_cast<int>(std::floor(360.0 / g.longitude_step_deg + 1e-9));
  for (int k = 0; k < n; ++k) {
    const double lon = g.longitude_first_deg + k * g.longitude_step_deg;
    if (k > 0 && lon >= g.longitude_first_deg + 360.0 - 1e-9) break;
    out.push_back(lon);
  }
  return out;
}

void validateCell(const CellConfig& c) {
  positive("bar.nominal_length_mm", c.bar.nominal_length_mm);
  if (c.bar.extension_lengths_mm.empty()) bad("bar.extension_lengths_mm", "is empty");
  for (size_t i = 0; i < c.bar.extension_lengths_mm.size(); ++i)
    nonNegative("bar.extension_lengths_mm[" + std::to_string(i) + "]",
                c.bar.extension_lengths_mm[i]);
  positive("bar.max_deflection_mm", c.bar.max_deflection_mm);

  if (c.connections.empty()) bad("connections", "is empty");
  for (size_t i = 0; i < c.connections.size(); ++i) {
    const Connection& k = c.connections[i];
    if (k.ball_index < 0 || k.ball_index >= kBallCount || k.chuck_index < 0 ||
        k.chuck_index >= kChuckCount)
      bad("connections[" + std::to_string(i) + "]", "no such ball or chuck");
    for (size_t j = 0; j < i; ++j)
      if (c.connections[j] == k)
        bad("connections[" + std::to_string(i) + "]", connectionName(k) + " is listed twice");
  }

  inRange("grid.latitude_first_deg", c.grid.latitude_first_deg, 0, 90);
  inRange("grid.latitude_last_deg", c.grid.latitude_last_deg, 0, 90);
  if (c.grid.latitude_last_deg > 90 - 1e-6)
    bad("grid.latitude_last_deg",
        "must be below 90: at the pole every longitude is the same point");
  if (c.grid.latitude_last_deg < c.grid.latitude_first_deg)
    bad("grid.latitude_last_deg", "is below grid.latitude_first_deg: the grid is empty");
  positive("grid.latitude_step_deg", c.grid.latitude_step_deg);
  inRange("grid.longitude_first_deg", c.grid.longitude_first_deg, -360, 360);
  inRange("grid.longitude_step_deg", c.grid.longitude_step_deg, 1e-3, 360);

  inRange("tool.approach_pitch_deg", c.tool.approach_pitch_deg, -90, 90);
  nonNegative("tool.pitch_variation_deg", c.tool.pitch_variation_deg);
  inRange("tool.approach_yaw_deg", c.tool.approach_yaw_deg, -90, 90);
  nonNegative("tool.yaw_variation_deg", c.tool.yaw_variation_deg);
  inRange("tool.roll_deg", c.tool.roll_deg, -360, 360);
  nonNegative("tool.roll_variation_deg", c.tool.roll_variation_deg);
  inRange("tool.min_bar_tool_angle_deg", c.tool.min_bar_tool_angle_deg, 0, 170);

  if (c.arm_configuration != "auto" && !parseArmConfig(c.arm_configuration))
    bad("arm_configuration",
        "'" + c.arm_configuration + "' is neither auto nor one of " + armConfigNames());
  inRange("connect.lat_deg", c.connect_lat_deg, 0, 90);
  inRange("connect.lon_deg", c.connect_lon_deg, -360, 360);

  nonNegative("margins.joint_limit_deg", c.margins.joint_limit_deg);
  inRange("margins.wrist_singularity_deg", c.margins.wrist_singularity_deg, 0, 89);
  inRange("margins.elbow_singularity_deg", c.margins.elbow_singularity_deg, 0, 89);
  nonNegative("margins.shoulder_singularity_mm", c.margins.shoulder_singularity_mm);
  nonNegative("margins.bar_clearance_mm", c.margins.bar_clearance_mm);
  if (!std::isfinite(c.margins.table_clearance_mm))
    bad("margins.table_clearance_mm", "not a finite number");

  positive("motion.joint_speed_deg_per_s", c.motion.joint_speed_deg_per_s);
  nonNegative("motion.move_overhead_s", c.motion.move_overhead_s);
  nonNegative("motion.settle_s", c.motion.settle_s);
  nonNegative("motion.swap_s", c.motion.swap_s);
  positive("motion.via_tolerance_mm", c.motion.via_tolerance_mm);
  inRange("motion.blend_deg", c.motion.blend_deg, 0, 30);
  if (c.motion.via_tolerance_mm >= c.bar.max_deflection_mm)
    bad("motion.via_tolerance_mm", "must be below bar.max_deflection_mm (" +
                                       std::to_string(c.bar.max_deflection_mm) +
                                       "), or the plan alone may use up the bar's range");
  inRange("motion.sample_step_mm", c.motion.sample_step_mm, 0.01, 1.0);

  nonNegative("model_uncertainty.translation_sigma_mm", c.uncertainty.translation_sigma_mm);
  nonNegative("model_uncertainty.link_angle_sigma_deg", c.uncertainty.link_angle_sigma_deg);
  nonNegative("model_uncertainty.joint_offset_sigma_deg", c.uncertainty.joint_offset_sigma_deg);
  nonNegative("model_uncertainty.gain_sigma", c.uncertainty.gain_sigma);
  inRange("model_uncertainty.models", c.uncertainty.models, 0, 10000);
  const WorkVolume& w = c.work_volume;
  for (int a = 0; a < 3; ++a)
    if (!(w.box_min_mm[a] < w.box_max_mm[a]))
      bad("work_volume.box_max_mm[" + std::to_string(a) + "]",
          "must be above work_volume.box_min_mm[" + std::to_string(a) + "]");
  const std::pair<const char*, std::array<double, 2>> ranges[] = {
      {"work_volume.rz_range_deg", w.rz_range_deg},
      {"work_volume.ry_range_deg", w.ry_range_deg},
      {"work_volume.rx_range_deg", w.rx_range_deg}};
  for (const auto& [key, range] : ranges) {
    inRange(std::string(key) + "[0]", range[0], -360, 360);
    inRange(std::string(key) + "[1]", range[1], -360, 360);
    if (range[1] < range[0]) bad(key, "[min, max] with min above max");
  }
  inRange("work_volume.poses", w.poses, 1, 100000);
}

}  // namespace robocal
