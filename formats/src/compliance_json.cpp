#include <robocal/formats/compliance_json.hpp>

#include <cmath>

namespace robocal {
namespace {

using Object = jsonread::Object<FormatError>;
using ojson = nlohmann::ordered_json;

Eigen::Vector3d point(const Object& o, const nlohmann::json& v, const std::string& path) {
  const nlohmann::json& a = o.reader().array(v, path, 3);
  Eigen::Vector3d p;
  for (int i = 0; i < 3; ++i) p[i] = o.reader().number(a[i], jsonread::indexPath(path, i));
  return p;
}

ojson vec(const Eigen::Vector3d& p) {
  return ojson::array({p.x(), p.y(), p.z()});
}

}  // namespace

void readJointNumbers(Object& o, const std::string& key, std::array<double, kJointCount>& out,
                      double lo, double hi) {
  const nlohmann::json* v = o.find(key);
  if (!v) return;
  const nlohmann::json& a = o.reader().array(*v, o.path(key), kJointCount);
  for (int j = 0; j < kJointCount; ++j)
    out[j] = o.reader().number(a[j], jsonread::indexPath(o.path(key), j), lo, hi);
}

void readComplianceKeys(Object& o, JointCompliance& c) {
  readJointNumbers(o, "compliance_deg_per_nm", c.deg_per_nm, -0.1, 0.1);
  GravityLoad& g = c.load;
  readJointNumbers(o, "link_mass_kg", g.link_mass_kg, 0, 1000);
  if (const nlohmann::json* v = o.find("link_com_mm")) {
    const nlohmann::json& a = o.reader().array(*v, o.path("link_com_mm"), kJointCount);
    for (int j = 0; j < kJointCount; ++j)
      g.link_com_mm[j] = point(o, a[j], jsonread::indexPath(o.path("link_com_mm"), j));
  }
  o.get("payload_kg", g.payload_kg, 0, 1000);
  if (const nlohmann::json* v = o.find("payload_com_mm"))
    g.payload_com_mm = point(o, *v, o.path("payload_com_mm"));
  if (const nlohmann::json* v = o.find("gravity_direction")) {
    g.gravity_direction = point(o, *v, o.path("gravity_direction"));
    const double norm = g.gravity_direction.norm();
    if (!(norm >= 1e-9 && std::isfinite(norm)))
      o.fail("gravity_direction", "expected a direction: not zero, not too large to normalise");
    g.gravity_direction.normalize();
  }
}

void writeComplianceKeys(ojson& out, const JointCompliance& c) {
  ojson coms = ojson::array();
  for (const Eigen::Vector3d& com : c.load.link_com_mm) coms.push_back(vec(com));
  out["compliance_deg_per_nm"] = c.deg_per_nm;
  out["link_mass_kg"] = c.load.link_mass_kg;
  out["link_com_mm"] = coms;
  out["payload_kg"] = c.load.payload_kg;
  out["payload_com_mm"] = vec(c.load.payload_com_mm);
  out["gravity_direction"] = vec(c.load.gravity_direction);
}

}  // namespace robocal
