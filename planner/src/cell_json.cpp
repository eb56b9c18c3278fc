#include <robocal/planner/cell_json.hpp>

#include <robocal/jsonread/strict_json.hpp>

#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace robocal {
namespace {

using nlohmann::json;
using Object = jsonread::Object<FormatError>;

constexpr const char* kUnknownKey = "unknown key (see docs/cell-format.md)";

// The section `key` of `parent` (when there) read by `read`, unknown keys refused.
template <typename Read>
void section(Object& parent, const std::string& key, Read read) {
  if (const json* v = parent.find(key)) {
    Object o(parent.reader(), *v, parent.path(key));
    read(o);
    o.finish(kUnknownKey);
  }
}

std::vector<Connection> connections(const jsonread::Reader<FormatError>& r, const json& v,
                                    const std::string& path) {
  auto parse = [&](const std::string& text, const std::string& where) {
    try {
      return parseConnections(text);
    } catch (const std::invalid_argument& e) {
      r.fail(where, e.what());
    }
  };
  if (v.is_string()) return parse(v.get<std::string>(), path);
  if (!v.is_array()) r.fail(path, "expected \"all\" or an array like [\"B1C1\", \"B2C3\"]");
  std::vector<Connection> all;
  for (size_t i = 0; i < v.size(); ++i) {
    const std::string where = jsonread::indexPath(path, i);
    const auto one = parse(r.string(v[i], where), where);
    all.insert(all.end(), one.begin(), one.end());
  }
  return all;
}

}  // namespace

CellConfig cellFromJson(const json& root, const std::string& source) {
  const jsonread::Reader<FormatError> r(source);
  CellConfig c;
  Object top(r, root, "");
  top.get("name", c.name);
  section(top, "bar", [&](Object& o) {
    o.get("nominal_length_mm", c.bar.nominal_length_mm);
    o.get("max_deflection_mm", c.bar.max_deflection_mm);
    if (const json* a = o.find("extension_lengths_mm")) {
      const std::string path = o.path("extension_lengths_mm");
      if (!a->is_array()) r.fail(path, "expected an array of lengths in mm");
      c.bar.extension_lengths_mm.clear();
      for (size_t i = 0; i < a->size(); ++i)
        c.bar.extension_lengths_mm.push_back(r.number((*a)[i], jsonread::indexPath(path, i)));
    }
  });
  if (const json* v = top.find("connections")) c.connections = connections(r, *v, "connections");
  section(top, "grid", [&](Object& o) {
    o.get("latitude_first_deg", c.grid.latitude_first_deg);
    o.get("latitude_last_deg", c.grid.latitude_last_deg);
    o.get("latitude_step_deg", c.grid.latitude_step_deg);
    o.get("longitude_first_deg", c.grid.longitude_first_deg);
    o.get("longitude_step_deg", c.grid.longitude_step_deg);
  });
  section(top, "tool", [&](Object& o) {
    o.get("approach_pitch_deg", c.tool.approach_pitch_deg);
    o.get("pitch_variation_deg", c.tool.pitch_variation_deg);
    o.get("approach_yaw_deg", c.tool.approach_yaw_deg);
    o.get("yaw_variation_deg", c.tool.yaw_variation_deg);
    o.get("roll_deg", c.tool.roll_deg);
    o.get("roll_variation_deg", c.tool.roll_variation_deg);
    o.get("min_bar_tool_angle_deg", c.tool.min_bar_tool_angle_deg);
  });
  top.get("arm_configuration", c.arm_configuration);
  section(top, "connect", [&](Object& o) {
    o.get("lat_deg", c.connect_lat_deg);
    o.get("lon_deg", c.connect_lon_deg);
  });
  section(top, "margins", [&](Object& o) {
    o.get("joint_limit_deg", c.margins.joint_limit_deg);
    o.get("wrist_singularity_deg", c.margins.wrist_singularity_deg);
    o.get("elbow_singularity_deg", c.margins.elbow_singularity_deg);
    o.get("shoulder_singularity_mm", c.margins.shoulder_singularity_mm);
    o.get("table_clearance_mm", c.margins.table_clearance_mm);
    o.get("bar_clearance_mm", c.margins.bar_clearance_mm);
  });
  section(top, "motion", [&](Object& o) {
    o.get("joint_speed_deg_per_s", c.motion.joint_speed_deg_per_s);
    o.get("move_overhead_s", c.motion.move_overhead_s);
    o.get("settle_s", c.motion.settle_s);
    o.get("swap_s", c.motion.swap_s);
    o.get("via_tolerance_mm", c.motion.via_tolerance_mm);
    o.get("through_vias", c.motion.through_vias);
    o.get("blend_deg", c.motion.blend_deg);
    o.get("sample_step_mm", c.motion.sample_step_mm);
    o.get("approach_deg", c.motion.approach_deg, 0, 1);
    o.get("revisit_every", c.motion.revisit_every, 0, 1000);
    o.get("reference_every_min", c.motion.reference_every_min, 0, 1000);
  });
  section(top, "model_uncertainty", [&](Object& o) {
    o.get("translation_sigma_mm", c.uncertainty.translation_sigma_mm);
    o.get("link_angle_sigma_deg", c.uncertainty.link_angle_sigma_deg);
    o.get("joint_offset_sigma_deg", c.uncertainty.joint_offset_sigma_deg);
    o.get("gain_sigma", c.uncertainty.gain_sigma);
    constexpr long long kLimit = 1000000000;
    o.get("models", c.uncertainty.models, -kLimit, kLimit);
    o.get("seed", c.uncertainty.seed, -kLimit, kLimit);
  });
  section(top, "work_volume", [&](Object& o) {
    WorkVolume& w = c.work_volume;
    auto numbers = [&](const char* key, auto& out) {
      const json* a = o.find(key);
      if (!a) return;
      const std::string path = o.path(key);
      if (!a->is_array() || a->size() != out.size())
        r.fail(path, "expected " + std::to_string(out.size()) + " numbers");
      for (size_t i = 0; i < out.size(); ++i)
        out[i] = r.number((*a)[i], jsonread::indexPath(path, i));
    };
    numbers("box_min_mm", w.box_min_mm);
    numbers("box_max_mm", w.box_max_mm);
    numbers("rz_range_deg", w.rz_range_deg);
    numbers("ry_range_deg", w.ry_range_deg);
    numbers("rx_range_deg", w.rx_range_deg);
    constexpr long long kLimit = 1000000000;
    o.get("poses", w.poses, -kLimit, kLimit);
    o.get("seed", w.seed, -kLimit, kLimit);
  });
  top.finish(kUnknownKey);
  try {
    validateCell(c);
  } catch (const std::invalid_argument& e) {
    throw FormatError(source + ": " + e.what());
  }
  return c;
}

CellConfig parseCell(const std::string& text, const std::string& source) {
  return cellFromJson(
      jsonread::parseText<FormatError>(text, source, "a cell file (docs/cell-format.md)"), source);
}

nlohmann::ordered_json cellToJson(const CellConfig& c) {
  nlohmann::ordered_json j;
  j["name"] = c.name;
  j["bar"] = {{"nominal_length_mm", c.bar.nominal_length_mm},
              {"extension_lengths_mm", c.bar.extension_lengths_mm},
              {"max_deflection_mm", c.bar.max_deflection_mm}};
  nlohmann::ordered_json conns = nlohmann::ordered_json::array();
  for (const Connection& k : c.connections) conns.push_back(connectionName(k));
  j["connections"] = conns;
  j["grid"] = {{"latitude_first_deg", c.grid.latitude_first_deg},
               {"latitude_last_deg", c.grid.latitude_last_deg},
               {"latitude_step_deg", c.grid.latitude_step_deg},
               {"longitude_first_deg", c.grid.longitude_first_deg},
               {"longitude_step_deg", c.grid.longitude_step_deg}};
  j["tool"] = {{"approach_pitch_deg", c.tool.approach_pitch_deg},
               {"pitch_variation_deg", c.tool.pitch_variation_deg},
               {"approach_yaw_deg", c.tool.approach_yaw_deg},
               {"yaw_variation_deg", c.tool.yaw_variation_deg},
               {"roll_deg", c.tool.roll_deg},
               {"roll_variation_deg", c.tool.roll_variation_deg},
               {"min_bar_tool_angle_deg", c.tool.min_bar_tool_angle_deg}};
  j["arm_configuration"] = c.arm_configuration;
  j["connect"] = {{"lat_deg", c.connect_lat_deg}, {"lon_deg", c.connect_lon_deg}};
  j["margins"] = {{"joint_limit_deg", c.margins.joint_limit_deg},
                  {"wrist_singularity_deg", c.margins.wrist_singularity_deg},
                  {"elbow_singularity_deg", c.margins.elbow_singularity_deg},
                  {"shoulder_singularity_mm", c.margins.shoulder_singularity_mm},
                  {"table_clearance_mm", c.margins.table_clearance_mm},
                  {"bar_clearance_mm", c.margins.bar_clearance_mm}};
  j["motion"] = {{"joint_speed_deg_per_s", c.motion.joint_speed_deg_per_s},
                 {"move_overhead_s", c.motion.move_overhead_s},
                 {"settle_s", c.motion.settle_s},
                 {"swap_s", c.motion.swap_s},
                 {"via_tolerance_mm", c.motion.via_tolerance_mm},
                 {"through_vias", c.motion.through_vias},
                 {"blend_deg", c.motion.blend_deg},
                 {"sample_step_mm", c.motion.sample_step_mm},
                 {"approach_deg", c.motion.approach_deg},
                 {"revisit_every", c.motion.revisit_every},
                 {"reference_every_min", c.motion.reference_every_min}};
  j["model_uncertainty"] = {{"translation_sigma_mm", c.uncertainty.translation_sigma_mm},
                            {"link_angle_sigma_deg", c.uncertainty.link_angle_sigma_deg},
                            {"joint_offset_sigma_deg", c.uncertainty.joint_offset_sigma_deg},
                            {"gain_sigma", c.uncertainty.gain_sigma},
                            {"models", c.uncertainty.models},
                            {"seed", c.uncertainty.seed}};
  const WorkVolume& w = c.work_volume;
  j["work_volume"] = {{"box_min_mm", w.box_min_mm},
                      {"box_max_mm", w.box_max_mm},
                      {"rz_range_deg", w.rz_range_deg},
                      {"ry_range_deg", w.ry_range_deg},
                      {"rx_range_deg", w.rx_range_deg},
                      {"poses", w.poses},
                      {"seed", w.seed}};
  return j;
}

CellConfig loadCellFile(const std::string& path) {
  return parseCell(readTextFile(path), path);
}

}  // namespace robocal
