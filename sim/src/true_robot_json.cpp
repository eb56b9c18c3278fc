#include <robocal/formats/error.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/jsonread/strict_json.hpp>
#include <robocal/sim/true_robot_json.hpp>

#include <nlohmann/json.hpp>

namespace robocal {
namespace {

using Object = jsonread::Object<FormatError>;
using ojson = nlohmann::ordered_json;

// Six numbers in [lo, hi], one per joint.
void getJoints(Object& o, const std::string& key, std::array<double, kJointCount>& out, double lo,
               double hi) {
  const nlohmann::json* v = o.find(key);
  if (!v) return;
  const nlohmann::json& a = o.reader().array(*v, o.path(key), kJointCount);
  for (int j = 0; j < kJointCount; ++j)
    out[j] = o.reader().number(a[j], jsonread::indexPath(o.path(key), j), lo, hi);
}

Eigen::Vector3d point(const Object& o, const nlohmann::json& v, const std::string& path) {
  const nlohmann::json& a = o.reader().array(v, path, 3);
  Eigen::Vector3d p;
  for (int i = 0; i < 3; ++i) p[i] = o.reader().number(a[i], jsonread::indexPath(path, i));
  return p;
}

ojson vec(const Eigen::Vector3d& p) {
  return ojson::array({p.x(), p.y(), p.z()});
}

nlohmann::json parseJsonFile(const std::string& path) {
  const std::string text = readTextFile(path);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw FormatError(path + ": not valid JSON: " + e.what());
  }
}

}  // namespace

Realism realismFromJson(const nlohmann::json& json, const std::string& source) {
  Object o(jsonread::Reader<FormatError>(source), json, "realism");
  Realism r;
  getJoints(o, "backlash_deg", r.backlash_deg, 0, 1);
  getJoints(o, "compliance_deg_per_nm", r.compliance_deg_per_nm, 0, 0.1);
  getJoints(o, "link_mass_kg", r.link_mass_kg, 0, 1000);
  if (const nlohmann::json* v = o.find("link_com_mm")) {
    const nlohmann::json& a = o.reader().array(*v, o.path("link_com_mm"), kJointCount);
    for (int j = 0; j < kJointCount; ++j)
      r.link_com_mm[j] = point(o, a[j], jsonread::indexPath(o.path("link_com_mm"), j));
  }
  o.get("payload_kg", r.payload_kg, 0, 1000);
  if (const nlohmann::json* v = o.find("payload_com_mm"))
    r.payload_com_mm = point(o, *v, o.path("payload_com_mm"));
  if (const nlohmann::json* v = o.find("gravity_direction")) {
    r.gravity_direction = point(o, *v, o.path("gravity_direction"));
    if (r.gravity_direction.norm() < 1e-9) o.fail("gravity_direction", "must not be zero");
    r.gravity_direction.normalize();
  }
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
  ojson coms = ojson::array();
  for (const Eigen::Vector3d& c : r.link_com_mm) coms.push_back(vec(c));
  return ojson{{"backlash_deg", r.backlash_deg},
               {"compliance_deg_per_nm", r.compliance_deg_per_nm},
               {"link_mass_kg", r.link_mass_kg},
               {"link_com_mm", coms},
               {"payload_kg", r.payload_kg},
               {"payload_com_mm", vec(r.payload_com_mm)},
               {"gravity_direction", vec(r.gravity_direction)},
               {"thermal_expansion_per_k", r.thermal_expansion_per_k},
               {"warmup_k", r.warmup_k},
               {"warmup_time_constant_min", r.warmup_time_constant_min},
               {"lvdt_gain_error", r.lvdt_gain_error},
               {"lvdt_nonlinearity_mm", r.lvdt_nonlinearity_mm},
               {"lvdt_half_travel_mm", r.lvdt_half_travel_mm},
               {"bar_length_error", r.bar_length_error}};
}

TrueRobot loadTruthFile(const std::string& path) {
  const nlohmann::json root = parseJsonFile(path);
  TrueRobot t;
  t.model = modelFromJson(root, path);
  if (root.is_object())
    if (const auto it = root.find("realism"); it != root.end())
      t.realism = realismFromJson(*it, path);
  return t;
}

Realism loadRealismFile(const std::string& path) {
  return realismFromJson(parseJsonFile(path), path);
}

Realism realismNamed(const std::string& ideal_typical_or_path) {
  if (ideal_typical_or_path == "ideal") return Realism::ideal();
  if (ideal_typical_or_path == "typical") return Realism::puma560Typical();
  return loadRealismFile(ideal_typical_or_path);
}

void saveTruthFile(const std::string& path, const TrueRobot& truth) {
  ojson out = modelToJson(truth.model);
  if (!truth.realism.isIdeal()) out["realism"] = realismToJson(truth.realism);
  writeTextFileAtomic(path, out.dump(2) + "\n");
}

}  // namespace robocal
