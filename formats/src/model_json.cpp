#include <robocal/formats/model_json.hpp>

#include <cmath>
#include <nlohmann/json.hpp>

namespace robocal {
namespace {

using nlohmann::json;

const char* typeName(const json& j) {
  return j.type_name();
}

// A value for an error message: a number or a string as written, an array or object by its size
// (dumping a deeply nested value recursed once per level and overflowed the stack).
std::string describe(const json& j) {
  if (j.is_array()) return "an array of " + std::to_string(j.size());
  if (j.is_object()) return "an object";
  return j.dump();
}

class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& where, const std::string& problem) const {
    throw FormatError(source_ + ": " + where + ": " + problem);
  }

  const json& member(const json& obj, const std::string& where, const char* key) const {
    const auto it = obj.find(key);
    if (it == obj.end()) fail(where.empty() ? key : where + "." + key, "missing");
    return *it;
  }

  double number(const json& obj, const std::string& where, const char* key) const {
    const std::string path = where.empty() ? key : where + "." + key;
    return numberValue(member(obj, where, key), path);
  }

  double numberValue(const json& value, const std::string& path) const {
    if (!value.is_number()) fail(path, std::string("expected a number, got ") + typeName(value));
    const double v = value.get<double>();
    if (!std::isfinite(v)) fail(path, "not a finite number");
    return v;
  }

  const json& array(const json& obj, const char* key, size_t count) const {
    const json& a = member(obj, "", key);
    if (!a.is_array()) fail(key, std::string("expected an array, got ") + typeName(a));
    if (a.size() != count)
      fail(key, "expected " + std::to_string(count) + " entries, got " + std::to_string(a.size()));
    return a;
  }

  const json& object(const json& value, const std::string& path) const {
    if (!value.is_object()) fail(path, std::string("expected an object, got ") + typeName(value));
    return value;
  }

  Eigen::Vector3d point(const json& value, const std::string& path) const {
    if (!value.is_array() || value.size() != 3)
      fail(path, "expected [x, y, z] in mm, got " + describe(value));
    return {numberValue(value[0], path + "[0]"), numberValue(value[1], path + "[1]"),
            numberValue(value[2], path + "[2]")};
  }

  std::string optionalString(const json& obj, const std::string& where, const char* key,
                             std::string fallback) const {
    const auto it = obj.find(key);
    if (it == obj.end()) return fallback;
    if (!it->is_string())
      fail(where + "." + key, std::string("expected a string, got ") + typeName(*it));
    return it->get<std::string>();
  }

 private:
  std::string source_;
};

}  // namespace

Model modelFromJson(const json& root, const std::string& source) {
  Reader r(source);
  r.object(root, "top level");
  Model m;
  m.name = r.optionalString(root, "", "name", "");

  const json& links = r.array(root, "links", kLinkCount);
  for (int k = 0; k < kLinkCount; ++k) {
    const std::string where = "links[" + std::to_string(k) + "]";
    const json& l = r.object(links[k], where);
    LinkParams& link = m.links[k];
    link.name = r.optionalString(l, where, "name", "L" + std::to_string(k));
    link.x_mm = r.number(l, where, "x");
    link.y_mm = r.number(l, where, "y");
    link.z_mm = r.number(l, where, "z");
    link.rz_deg = r.number(l, where, "rz");
    link.ry_deg = r.number(l, where, "ry");
    link.rx_deg = r.number(l, where, "rx");
  }

  const json& joints = r.array(root, "joints", kJointCount);
  for (int j = 0; j < kJointCount; ++j) {
    const std::string where = "joints[" + std::to_string(j) + "]";
    const json& jo = r.object(joints[j], where);
    JointParams& joint = m.joints[j];
    joint.name = r.optionalString(jo, where, "name", "J" + std::to_string(j + 1));
    joint.offset_deg = r.number(jo, where, "offset");
    joint.gain = r.number(jo, where, "gain");
    joint.min_deg = r.number(jo, where, "min");
    joint.max_deg = r.number(jo, where, "max");
    if (joint.gain == 0.0) r.fail(where + ".gain", "must not be zero");
    if (joint.min_deg >= joint.max_deg) r.fail(where, "min must be less than max");
  }

  const json& balls = r.array(root, "balls", kBallCount);
  for (int b = 0; b < kBallCount; ++b)
    m.balls_mm[b] = r.point(balls[b], "balls[" + std::to_string(b) + "]");
  const json& chucks = r.array(root, "chucks", kChuckCount);
  for (int c = 0; c < kChuckCount; ++c)
    m.chucks_mm[c] = r.point(chucks[c], "chucks[" + std::to_string(c) + "]");
  return m;
}

Model parseModel(const std::string& text, const std::string& source) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {  // syntax errors, and numbers too large for a double
    throw FormatError(source + ": not valid JSON: " + e.what());
  }
  return modelFromJson(root, source);
}

nlohmann::ordered_json modelToJson(const Model& m) {
  using ojson = nlohmann::ordered_json;
  ojson out = ojson::object();
  out["name"] = m.name;
  ojson links = ojson::array();
  for (const LinkParams& l : m.links)
    links.push_back(ojson{{"name", l.name},
                          {"x", l.x_mm},
                          {"y", l.y_mm},
                          {"z", l.z_mm},
                          {"rz", l.rz_deg},
                          {"ry", l.ry_deg},
                          {"rx", l.rx_deg}});
  out["links"] = links;
  ojson joints = ojson::array();
  for (const JointParams& j : m.joints)
    joints.push_back(ojson{{"name", j.name},
                           {"offset", j.offset_deg},
                           {"gain", j.gain},
                           {"min", j.min_deg},
                           {"max", j.max_deg}});
  out["joints"] = joints;
  ojson balls = ojson::array(), chucks = ojson::array();
  for (const auto& b : m.balls_mm) balls.push_back(ojson::array({b.x(), b.y(), b.z()}));
  for (const auto& c : m.chucks_mm) chucks.push_back(ojson::array({c.x(), c.y(), c.z()}));
  out["balls"] = balls;
  out["chucks"] = chucks;
  return out;
}

std::string formatModel(const Model& model) {
  return modelToJson(model).dump(2) + "\n";
}

Model loadModelFile(const std::string& path) {
  return parseModel(readTextFile(path), path);
}

void saveModelFile(const std::string& path, const Model& model) {
  writeTextFileAtomic(path, formatModel(model));
}

}  // namespace robocal
