#include <robocal/formats/compliance_json.hpp>
#include <robocal/formats/error.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/jsonread/strict_json.hpp>
#include <robocal/sim/true_robot_json.hpp>

#include <nlohmann/json.hpp>

namespace robocal {
namespace {

using Object = jsonread::Object<FormatError>;
using ojson = nlohmann::ordered_json;

nlohmann::json parseJsonFile(const std::string& path) {
  return jsonread::parseText<FormatError>(readTextFile(path), path,
                                          "a truth or realism file (docs/realism.md)");
}

}  // namespace

Realism realismFromJson(const nlohmann::json& json, const std::string& source) {
  Object o(jsonread::Reader<FormatError>(source), json, "realism");
  Realism r;
  readJointNumbers(o, "backlash_deg", r.backlash_deg, 0, 1);
  readComplianceKeys(o, r.compliance);
  o.get("thermal_expansion_per_k", r.thermal_expansion_per_k, 0, 1e-3);
  o.get("warmup_k", r.warmup_k, -50, 50);
  o.get("warmup_time_constant_min", r.warmup_time_constant_min, 1e-3, 1e4);
  o.get("lvdt_gain_error", r.lvdt_gain_error, -0.1, 0.1);
  o.get("lvdt_nonlinearity_mm", r.lvdt_nonlinearity_mm, -1, 1);
  o.get("lvdt_half_travel_mm", r.lvdt_half_travel_mm, 1e-3, 100);
  o.get("bar_length_error", r.bar_length_error, -0.01, 0.01);
  o.finish();
  return r;
}

ojson realismToJson(const Realism& r) {
  ojson out{{"backlash_deg", r.backlash_deg}};
  writeComplianceKeys(out, r.compliance);
  out["thermal_expansion_per_k"] = r.thermal_expansion_per_k;
  out["warmup_k"] = r.warmup_k;
  out["warmup_time_constant_min"] = r.warmup_time_constant_min;
  out["lvdt_gain_error"] = r.lvdt_gain_error;
  out["lvdt_nonlinearity_mm"] = r.lvdt_nonlinearity_mm;
  out["lvdt_half_travel_mm"] = r.lvdt_half_travel_mm;
  out["bar_length_error"] = r.bar_length_error;
  return out;
}

TrueRobot loadTruthFile(const std::string& path) {
  const nlohmann::json root = parseJsonFile(path);
  TrueRobot t;
  t.model = modelFromJson(root, path);
  if (t.model.compliance && t.model.compliance->twists())
    throw FormatError(path + ": compliance: a truth's compliance goes in its \"realism\"");
  // The realism twists the true robot, not its model; what gravity pulls on stays in the
  // realism (not twisting) for a --realism named later (realismNamed).
  if (t.model.compliance) t.realism.compliance.load = t.model.compliance->load;
  t.model.compliance.reset();
  if (root.is_object())
    if (const auto it = root.find("realism"); it != root.end())
      t.realism = realismFromJson(*it, path);
  return t;
}

Realism loadRealismFile(const std::string& path) {
  return realismFromJson(parseJsonFile(path), path);
}

Realism realismNamed(const std::string& ideal_typical_or_path, const GravityLoad& arm_load) {
  if (ideal_typical_or_path == "ideal") return Realism::ideal();
  if (ideal_typical_or_path == "typical") return Realism::typical(arm_load);
  return loadRealismFile(ideal_typical_or_path);
}

void saveTruthFile(const std::string& path, const TrueRobot& truth) {
  ojson out = modelToJson(truth.model);
  if (!truth.realism.isIdeal()) out["realism"] = realismToJson(truth.realism);
  writeTextFileAtomic(path, out.dump(2) + "\n");
}

}  // namespace robocal
