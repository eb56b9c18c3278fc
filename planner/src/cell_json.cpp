#include <robocal/planner/cell_json.hpp>

#include <cmath>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace robocal {
namespace {

using nlohmann::json;

class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
    throw FormatError(source_ + ": " + key + ": " + problem);
  }

  double number(const json& v, const std::string& key) const {
    if (!v.is_number()) fail(key, std::string("expected a number, got ") + v.type_name());
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail(key, "not a finite number");
    return d;
  }

  int integer(const json& v, const std::string& key) const {
    if (!v.is_number_integer())  // no dump() of an array or object: it recurses per level
      fail(key, "expected an integer, got " + (v.is_structured() ? v.type_name() : v.dump()));
    const auto i = v.get<long long>();
    if (i < -1000000000LL || i > 1000000000LL) fail(key, "out of range");
    return static_cast<int>(i);
  }

  std::string string(const json& v, const std::string& key) const {
    if (!v.is_string()) fail(key, std::string("expected a string, got ") + v.type_name());
    return v.get<std::string>();
  }

  // Calls the handler of each key of `obj`; unknown keys are errors.
  void object(const json& obj, const std::string& where,
              const std::map<std::string, std::function<void(const json&, const std::string&)>>&
                  handlers) const {
    if (!obj.is_object())
      fail(where.empty() ? "top level" : where,
           std::string("expected an object, got ") + obj.type_name());
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      const std::string key = where.empty() ? it.key() : where + "." + it.key();
      const auto h = handlers.find(it.key());
      if (h == handlers.end()) fail(key, "unknown key (see docs/cell-format.md)");
      h->second(it.value(), key);
    }
  }

 private:
  std::string source_;
};

}  // namespace

CellConfig cellFromJson(const json& root, const std::string& source) {
  const Reader r(source);
  CellConfig c;
  auto num = [&](double& target) {
    return [&r, &target](const json& v, const std::string& key) { target = r.number(v, key); };
  };
  r.object(root, "",
           {
               {"name", [&](const json& v, const std::string& k) { c.name = r.string(v, k); }},
               {"bar",
                [&](const json& v, const std::string& k) {
                  r.object(v, k,
                           {{"nominal_length_mm", num(c.bar.nominal_length_mm)},
                            {"max_deflection_mm", num(c.bar.max_deflection_mm)},
                            {"extension_lengths_mm", [&](const json& a, const std::string& key) {
                               if (!a.is_array()) r.fail(key, "expected an array of lengths in mm");
                               c.bar.extension_lengths_mm.clear();
                               for (size_t i = 0; i < a.size(); ++i)
                                 c.bar.extension_lengths_mm.push_back(
                                     r.number(a[i], key + "[" + std::to_string(i) + "]"));
                             }}});
                }},
               {"connections",
                [&](const json& v, const std::string& k) {
                  if (v.is_string()) {
                    try {
                      c.connections = parseConnections(v.get<std::string>());
                    } catch (const std::invalid_argument& e) {
                      r.fail(k, e.what());
                    }
                    return;
                  }
                  if (!v.is_array())
                    r.fail(k, "expected \"all\" or an array like [\"B1C1\", \"B2C3\"]");
                  c.connections.clear();
                  for (size_t i = 0; i < v.size(); ++i) {
                    const std::string key = k + "[" + std::to_string(i) + "]";
                    try {
                      const auto one = parseConnections(r.string(v[i], key));
                      c.connections.insert(c.connections.end(), one.begin(), one.end());
                    } catch (const std::invalid_argument& e) {
                      r.fail(key, e.what());
                    }
                  }
                }},
               {"grid",
                [&](const json& v, const std::string& k) {
                  r.object(v, k,
                           {{"latitude_first_deg", num(c.grid.latitude_first_deg)},
                            {"latitude_last_deg", num(c.grid.latitude_last_deg)},
                            {"latitude_step_deg", num(c.grid.latitude_step_deg)},
                            {"longitude_first_deg", num(c.grid.longitude_first_deg)},
                            {"longitude_step_deg", num(c.grid.longitude_step_deg)}});
                }},
               {"tool",
                [&](const json& v, const std::string& k) {
                  r.object(v, k,
                           {{"approach_pitch_deg", num(c.tool.approach_pitch_deg)},
                            {"pitch_variation_deg", num(c.tool.pitch_variation_deg)},
                            {"approach_yaw_deg", num(c.tool.approach_yaw_deg)},
                            {"yaw_variation_deg", num(c.tool.yaw_variation_deg)},
                            {"roll_deg", num(c.tool.roll_deg)},
                            {"roll_variation_deg", num(c.tool.roll_variation_deg)},
                            {"min_bar_tool_angle_deg", num(c.tool.min_bar_tool_angle_deg)}});
                }},
               {"arm_configuration",
                [&](const json& v, const std::string& k) { c.arm_configuration = r.string(v, k); }},
               {"connect",
                [&](const json& v, const std::string& k) {
                  r.object(
                      v, k,
                      {{"lat_deg", num(c.connect_lat_deg)}, {"lon_deg", num(c.connect_lon_deg)}});
                }},
               {"margins",
                [&](const json& v, const std::string& k) {
                  r.object(v, k,
                           {{"joint_limit_deg", num(c.margins.joint_limit_deg)},
                            {"wrist_singularity_deg", num(c.margins.wrist_singularity_deg)},
                            {"elbow_singularity_deg", num(c.margins.elbow_singularity_deg)},
                            {"shoulder_singularity_mm", num(c.margins.shoulder_singularity_mm)},
                            {"table_clearance_mm", num(c.margins.table_clearance_mm)},
                            {"bar_clearance_mm", num(c.margins.bar_clearance_mm)}});
                }},
               {"motion",
                [&](const json& v, const std::string& k) {
                  r.object(v, k,
                           {{"joint_speed_deg_per_s", num(c.motion.joint_speed_deg_per_s)},
                            {"move_overhead_s", num(c.motion.move_overhead_s)},
                            {"settle_s", num(c.motion.settle_s)},
                            {"via_tolerance_mm", num(c.motion.via_tolerance_mm)},
                            {"sample_step_mm", num(c.motion.sample_step_mm)}});
                }},
               {"model_uncertainty",
                [&](const json& v, const std::string& k) {
                  r.object(v, k,
                           {{"translation_sigma_mm", num(c.uncertainty.translation_sigma_mm)},
                            {"link_angle_sigma_deg", num(c.uncertainty.link_angle_sigma_deg)},
                            {"joint_offset_sigma_deg", num(c.uncertainty.joint_offset_sigma_deg)},
                            {"gain_sigma", num(c.uncertainty.gain_sigma)},
                            {"models",
                             [&](const json& x, const std::string& key) {
                               c.uncertainty.models = r.integer(x, key);
                             }},
                            {"seed", [&](const json& x, const std::string& key) {
                               c.uncertainty.seed = r.integer(x, key);
                             }}});
                }},
           });
  try {
    validateCell(c);
  } catch (const std::invalid_argument& e) {
    throw FormatError(source + ": " + e.what());
  }
  return c;
}

CellConfig parseCell(const std::string& text, const std::string& source) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {  // syntax errors, and numbers too large for a double
    throw FormatError(source + ": not valid JSON: " + e.what());
  }
  return cellFromJson(j, source);
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
                 {"via_tolerance_mm", c.motion.via_tolerance_mm},
                 {"sample_step_mm", c.motion.sample_step_mm}};
  j["model_uncertainty"] = {{"translation_sigma_mm", c.uncertainty.translation_sigma_mm},
                            {"link_angle_sigma_deg", c.uncertainty.link_angle_sigma_deg},
                            {"joint_offset_sigma_deg", c.uncertainty.joint_offset_sigma_deg},
                            {"gain_sigma", c.uncertainty.gain_sigma},
                            {"models", c.uncertainty.models},
                            {"seed", c.uncertainty.seed}};
  return j;
}

CellConfig loadCellFile(const std::string& path) {
  return parseCell(readTextFile(path), path);
}

}  // namespace robocal
