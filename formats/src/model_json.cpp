#include <robocal/formats/model_json.hpp>

#include <robocal/formats/compliance_json.hpp>
#include <robocal/jsonread/strict_json.hpp>
#include <robocal/kinematics/units.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <nlohmann/json.hpp>

namespace robocal {
namespace {

using nlohmann::json;

// A value for an error message: a number or a string as written, an array or object by its size
// (dumping a deeply nested value recursed once per level and overflowed the stack).
std::string describe(const json& j) {
  if (j.is_array()) return "an array of " + std::to_string(j.size());
  if (j.is_object()) return "an object";
  return j.dump();
}

// The model's vocabulary on the strict reader: required numbers, fixed-size arrays, points, and
// the provenance's optional members.
class Reader {
 public:
  explicit Reader(const std::string& source) : r_(source) {}

  [[noreturn]] void fail(const std::string& where, const std::string& problem) const {
    r_.fail(where, problem);
  }

  double number(const json& obj, const std::string& where, const char* key) const {
    return r_.number(r_.member(obj, where, key), jsonread::keyPath(where, key));
  }

  const json& array(const json& obj, const char* key, size_t count) const {
    return r_.array(r_.member(obj, "", key), key, count);
  }

  const json& object(const json& value, const std::string& path) const {
    return r_.object(value, path);
  }

  Eigen::Vector3d point(const json& value, const std::string& path) const {
    if (!value.is_array() || value.size() != 3)
      fail(path, "expected [x, y, z] in mm, got " + describe(value));
    return {r_.number(value[0], path + "[0]"), r_.number(value[1], path + "[1]"),
            r_.number(value[2], path + "[2]")};
  }

  std::string optionalString(const json& obj, const std::string& where, const char* key,
                             std::string fallback) const {
    const auto it = obj.find(key);
    return it == obj.end() ? fallback : r_.string(*it, jsonread::keyPath(where, key));
  }

  std::vector<std::string> optionalStrings(const json& obj, const std::string& where,
                                           const char* key) const {
    const auto it = obj.find(key);
    if (it == obj.end()) return {};
    const std::string path = jsonread::keyPath(where, key);
    r_.array(*it, path);
    return r_.strings(*it, path);
  }

  // A whole number from 0 to `max`; 0 when the key is absent.
  long long optionalCount(const json& obj, const std::string& where, const char* key,
                          long long max) const {
    const auto it = obj.find(key);
    if (it == obj.end()) return 0;
    const std::string path = jsonread::keyPath(where, key);
    const double v = r_.number(*it, path);
    if (v < 0 || v > static_cast<double>(max) || v != std::floor(v))
      fail(path, "expected a whole number from 0 to " + std::to_string(max));
    return static_cast<long long>(v);
  }

  double optionalNumber(const json& obj, const std::string& where, const char* key) const {
    return obj.contains(key) ? number(obj, where, key) : 0.0;
  }

  // A field of the parameter layout (kLinkFields, kJointFields): required, or the value its
  // `absent` says an older file stands for.
  template <typename Params>
  double parameter(const json& obj, const std::string& where, const ParamField<Params>& f) const {
    if (!obj.contains(f.key) && !std::isnan(f.absent)) return f.absent;
    return number(obj, where, f.key);
  }

 private:
  jsonread::Reader<FormatError> r_;
};

ModelProvenance provenanceFromJson(const Reader& r, const json& value) {
  const std::string where = "provenance";
  r.object(value, where);
  ModelProvenance p;
  p.run_id = r.optionalString(value, where, "run_id", "");
  p.date_utc = r.optionalString(value, where, "date_utc", "");
  p.nominal_name = r.optionalString(value, where, "nominal", "");
  p.samples_files = r.optionalStrings(value, where, "samples_files");
  p.samples = static_cast<std::size_t>(r.optionalCount(value, where, "n_samples", 1LL << 50));
  p.rms_mm = r.optionalNumber(value, where, "rms_mm");
  p.rank = static_cast<int>(r.optionalCount(value, where, "rank", kParamCount));
  p.expected_rank = static_cast<int>(r.optionalCount(value, where, "expected_rank", kParamCount));
  p.robocal_version = r.optionalString(value, where, "robocal_version", "");
  p.warnings = r.optionalStrings(value, where, "warnings");
  if (const auto it = value.find("nominal_parameters"); it != value.end()) {
    const std::string at = where + ".nominal_parameters";
    r.object(*it, at);
    ParamVector params;
    for (int i = 0; i < kParamCount; ++i) {
      const double v = r.number(*it, at, paramName(i).c_str());
      params[i] = paramKind(i) == ParamKind::kAngle ? v / kDegPerRad : v;
    }
    for (const auto& [name, unused] : it->items())
      if (paramIndexByName(name) < 0)
        r.fail(at + "." + name, "is not a parameter of the model (L0.x ... J6.gain)");
    p.nominal_params = params;
  }
  if (const auto it = value.find("measured_joints_deg"); it != value.end()) {
    const std::string at = where + ".measured_joints_deg";
    r.array(value, "measured_joints_deg", kJointCount);
    std::array<std::array<double, 2>, kJointCount> ranges{};
    for (int j = 0; j < kJointCount; ++j) {
      const std::string item = at + "[" + std::to_string(j) + "]";
      const json& pair = (*it)[j];
      if (!pair.is_array() || pair.size() != 2 || !pair[0].is_number() || !pair[1].is_number() ||
          pair[0].get<double>() > pair[1].get<double>())
        r.fail(item, "expected [min, max] in deg with min <= max");
      ranges[j] = {pair[0].get<double>(), pair[1].get<double>()};
    }
    p.measured_joints_deg = ranges;
  }
  p.approach_deg = r.optionalNumber(value, where, "approach_deg");
  if (!(p.approach_deg >= 0 && p.approach_deg <= 1))
    r.fail(where + ".approach_deg", "expected 0 to 1 (deg)");
  p.unmodelled_mm = r.optionalNumber(value, where, "unmodelled_mm");
  if (!(p.unmodelled_mm >= 0))  // finite: number() refuses the rest
    r.fail(where + ".unmodelled_mm", "expected 0 or more (mm)");
  return p;
}

nlohmann::ordered_json provenanceToJson(const ModelProvenance& p) {
  using ojson = nlohmann::ordered_json;
  ojson out = ojson::object();
  if (!p.run_id.empty()) out["run_id"] = p.run_id;
  out["date_utc"] = p.date_utc;
  out["nominal"] = p.nominal_name;
  out["samples_files"] = p.samples_files;
  out["n_samples"] = p.samples;
  out["rms_mm"] = p.rms_mm;
  out["rank"] = p.rank;
  out["expected_rank"] = p.expected_rank;
  out["robocal_version"] = p.robocal_version;
  out["warnings"] = p.warnings;
  if (p.nominal_params) {
    ojson params = ojson::object();
    for (int i = 0; i < kParamCount; ++i)
      params[paramName(i)] = paramInterfaceValue(*p.nominal_params, i);
    out["nominal_parameters"] = params;
  }
  if (p.measured_joints_deg) {
    ojson ranges = ojson::array();
    for (const auto& range : *p.measured_joints_deg) ranges.push_back({range[0], range[1]});
    out["measured_joints_deg"] = ranges;
  }
  if (p.approach_deg > 0) out["approach_deg"] = p.approach_deg;
  if (p.unmodelled_mm > 0) out["unmodelled_mm"] = p.unmodelled_mm;
  return out;
}

// The covariance block: the estimated parameters by name and their covariance in interface units
// (mm, deg, gain, and deg/(N m) for a joint's twist "J2.compliance"); ParamVector units inside,
// the twists after the 54 (Model::covariance).
double interfaceScale(int index) {
  return index < kParamCount && paramKind(index) == ParamKind::kAngle ? kDegPerRad : 1.0;
}

// A covariance row's index from its name: one of the 54, or kParamCount + j for
// "J<j+1>.compliance"; -1 for neither.
int covarianceIndex(const std::string& name) {
  if (name.size() == 13 && name[0] == 'J' && name[1] >= '1' && name[1] <= '6' &&
      name.compare(2, std::string::npos, ".compliance") == 0)
    return twistCovarianceIndex(name[1] - '1');
  return paramIndexByName(name);
}

std::string covarianceName(int index) {
  return index < kParamCount ? paramName(index)
                             : "J" + std::to_string(index - kParamCount + 1) + ".compliance";
}

Eigen::MatrixXd covarianceFromJson(const Reader& r, const json& value) {
  const std::string where = "covariance";
  r.object(value, where);
  const auto names_it = value.find("parameters");
  const auto matrix_it = value.find("matrix");
  if (names_it == value.end()) r.fail(where, "missing \"parameters\"");
  if (matrix_it == value.end()) r.fail(where, "missing \"matrix\"");
  if (!names_it->is_array()) r.fail(where + ".parameters", "expected an array of parameter names");
  std::vector<int> index;
  for (size_t k = 0; k < names_it->size(); ++k) {
    const std::string path = where + ".parameters[" + std::to_string(k) + "]";
    const json& name = (*names_it)[k];
    if (!name.is_string()) r.fail(path, "expected a parameter name such as \"J2.offset\"");
    const int i = covarianceIndex(name.get<std::string>());
    if (i < 0) r.fail(path, "unknown parameter \"" + name.get<std::string>() + "\"");
    for (int seen : index)
      if (seen == i) r.fail(path, "\"" + name.get<std::string>() + "\" is listed twice");
    index.push_back(i);
  }
  const size_t n = index.size();
  if (!matrix_it->is_array() || matrix_it->size() != n)
    r.fail(where + ".matrix", "expected " + std::to_string(n) + " rows, one per parameter");
  const bool twists =
      std::any_of(index.begin(), index.end(), [](int i) { return i >= kParamCount; });
  const int size = twists ? kParamCount + kJointCount : kParamCount;
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(size, size);
  for (size_t a = 0; a < n; ++a) {
    const std::string row_path = where + ".matrix[" + std::to_string(a) + "]";
    const json& row = (*matrix_it)[a];
    if (!row.is_array() || row.size() != n)
      r.fail(row_path, "expected " + std::to_string(n) + " numbers");
    for (size_t b = 0; b < n; ++b) {
      const std::string path = row_path + "[" + std::to_string(b) + "]";
      if (!row[b].is_number()) r.fail(path, "expected a number, got " + describe(row[b]));
      cov(index[a], index[b]) =
          row[b].get<double>() / (interfaceScale(index[a]) * interfaceScale(index[b]));
    }
    if (!(cov(index[a], index[a]) >= 0)) r.fail(row_path, "a negative variance on the diagonal");
  }
  const double largest = cov.cwiseAbs().maxCoeff();
  if ((cov - cov.transpose()).cwiseAbs().maxCoeff() > 1e-9 * largest)
    r.fail(where + ".matrix", "not symmetric");
  return cov;
}

nlohmann::ordered_json covarianceToJson(const Eigen::MatrixXd& cov) {
  using ojson = nlohmann::ordered_json;
  std::vector<int> index;
  for (int i = 0; i < cov.rows(); ++i)
    if (cov(i, i) > 0) index.push_back(i);
  ojson names = ojson::array(), matrix = ojson::array();
  for (int a : index) {
    names.push_back(covarianceName(a));
    ojson row = ojson::array();
    for (int b : index) row.push_back(cov(a, b) * interfaceScale(a) * interfaceScale(b));
    matrix.push_back(row);
  }
  const bool twists = cov.rows() > kParamCount;
  return ojson{{"units", twists ? "products of the parameters' units: mm, deg, gain, deg/(N m)"
                                : "products of the parameters' units: mm, deg, gain"},
               {"parameters", names},
               {"matrix", matrix}};
}

// dump(2) puts every number on a line of its own; arrays of numbers go on one line instead, so
// that points and the covariance's rows read as rows.
std::string compactNumberArrays(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  size_t i = 0;
  bool in_string = false;
  while (i < text.size()) {
    const char at = text[i];
    if (in_string) {  // strings are copied as they are, escapes included
      out += at;
      if (at == '\\' && i + 1 < text.size())
        out += text[++i];
      else if (at == '"')
        in_string = false;
      ++i;
      continue;
    }
    if (at == '"') in_string = true;
    if (at == '[') {
      size_t j = i + 1;
      bool numbers_only = true;
      while (j < text.size() && text[j] != ']') {
        const char c = text[j];
        if (!(std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.' ||
              c == 'e' || c == 'E' || c == ',' || std::isspace(static_cast<unsigned char>(c)))) {
          numbers_only = false;
          break;
        }
        ++j;
      }
      if (numbers_only && j < text.size() && j > i + 1) {
        out += '[';
        bool pending_space = false;
        for (size_t k = i + 1; k < j; ++k) {
          const char c = text[k];
          if (std::isspace(static_cast<unsigned char>(c))) continue;
          if (pending_space) out += ' ';
          pending_space = false;
          out += c;
          if (c == ',') pending_space = true;
        }
        out += ']';
        i = j + 1;
        continue;
      }
    }
    out += text[i++];
  }
  return out;
}

}  // namespace

Model modelFromJson(const json& root, const std::string& source) {
  Reader r(source);
  r.object(root, "top level");
  Model m;
  m.name = r.optionalString(root, "", "name", "");
  if (const auto it = root.find("provenance"); it != root.end())
    m.provenance = provenanceFromJson(r, *it);

  const json& links = r.array(root, "links", kLinkCount);
  for (int k = 0; k < kLinkCount; ++k) {
    const std::string where = "links[" + std::to_string(k) + "]";
    const json& l = r.object(links[k], where);
    LinkParams& link = m.links[k];
    link.name = r.optionalString(l, where, "name", "L" + std::to_string(k));
    for (const auto& f : kLinkFields) link.*f.field = r.parameter(l, where, f);
  }

  const json& joints = r.array(root, "joints", kJointCount);
  for (int j = 0; j < kJointCount; ++j) {
    const std::string where = "joints[" + std::to_string(j) + "]";
    const json& jo = r.object(joints[j], where);
    JointParams& joint = m.joints[j];
    joint.name = r.optionalString(jo, where, "name", "J" + std::to_string(j + 1));
    for (const auto& f : kJointFields) joint.*f.field = r.parameter(jo, where, f);
    joint.min_deg = r.number(jo, where, "min");
    joint.max_deg = r.number(jo, where, "max");
    if (joint.gain == 0.0) r.fail(where + ".gain", "must not be zero");
    if (joint.min_deg >= joint.max_deg) r.fail(where, "min must be less than max");
    joint.velocity_deg_per_s = r.optionalNumber(jo, where, "velocity_deg_per_s");
    joint.effort_nm = r.optionalNumber(jo, where, "effort_nm");
    if (!(joint.velocity_deg_per_s >= 0 && joint.velocity_deg_per_s <= kMaxVelocityDegPerS))
      r.fail(where + ".velocity_deg_per_s", "expected 0 (not known) to 100000 (deg/s)");
    if (!(joint.effort_nm >= 0 && joint.effort_nm <= kMaxEffortNm))
      r.fail(where + ".effort_nm", "expected 0 (not known) to 1000000 (N m)");
  }

  const json& balls = r.array(root, "balls", kBallCount);
  for (int b = 0; b < kBallCount; ++b)
    m.balls_mm[b] = r.point(balls[b], "balls[" + std::to_string(b) + "]");
  const json& chucks = r.array(root, "chucks", kChuckCount);
  for (int c = 0; c < kChuckCount; ++c)
    m.chucks_mm[c] = r.point(chucks[c], "chucks[" + std::to_string(c) + "]");
  if (const auto it = root.find("compliance"); it != root.end()) {
    jsonread::Object<FormatError> o(jsonread::Reader<FormatError>(source), *it, "compliance");
    JointCompliance c;
    readComplianceKeys(o, c);
    o.finish();
    m.compliance = c;
  }
  if (const auto it = root.find("covariance"); it != root.end()) {
    m.covariance = covarianceFromJson(r, *it);
    if (m.covariance->rows() > kParamCount && !m.compliance)
      r.fail("covariance.parameters",
             "a joint's twist (\"J<n>.compliance\") in a model without a \"compliance\" object");
  }
  return m;
}

Model parseModel(const std::string& text, const std::string& source) {
  return modelFromJson(
      jsonread::parseText<FormatError>(text, source, "a model (docs/model-format.md)"), source);
}

nlohmann::ordered_json modelToJson(const Model& m) {
  using ojson = nlohmann::ordered_json;
  ojson out = ojson::object();
  out["name"] = m.name;
  if (m.provenance) out["provenance"] = provenanceToJson(*m.provenance);
  ojson links = ojson::array();
  for (const LinkParams& l : m.links) {
    ojson link{{"name", l.name}};
    for (const auto& f : kLinkFields) link[f.key] = l.*f.field;
    links.push_back(link);
  }
  out["links"] = links;
  ojson joints = ojson::array();
  for (const JointParams& j : m.joints) {
    ojson joint{{"name", j.name}};
    for (const auto& f : kJointFields) joint[f.key] = j.*f.field;
    joint["min"] = j.min_deg;
    joint["max"] = j.max_deg;
    if (j.velocity_deg_per_s > 0) joint["velocity_deg_per_s"] = j.velocity_deg_per_s;
    if (j.effort_nm > 0) joint["effort_nm"] = j.effort_nm;
    joints.push_back(joint);
  }
  out["joints"] = joints;
  ojson balls = ojson::array(), chucks = ojson::array();
  for (const auto& b : m.balls_mm) balls.push_back(ojson::array({b.x(), b.y(), b.z()}));
  for (const auto& c : m.chucks_mm) chucks.push_back(ojson::array({c.x(), c.y(), c.z()}));
  out["balls"] = balls;
  out["chucks"] = chucks;
  if (m.compliance) {
    ojson compliance = ojson::object();
    writeComplianceKeys(compliance, *m.compliance);
    out["compliance"] = compliance;
  }
  if (m.covariance) out["covariance"] = covarianceToJson(*m.covariance);
  return out;
}

std::string formatModel(const Model& model) {
  return compactNumberArrays(modelToJson(model).dump(2)) + "\n";
}

Model loadModelFile(const std::string& path) {
  return parseModel(readTextFile(path), path);
}

void saveModelFile(const std::string& path, const Model& model) {
  writeTextFileAtomic(path, formatModel(model));
}

}  // namespace robocal
