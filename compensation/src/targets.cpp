#include <robocal/compensation/targets.hpp>

#include <robocal/formats/csv.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <set>

namespace robocal {
namespace {

constexpr std::array<const char*, 6> kPoseColumns = {"x_mm",   "y_mm",   "z_mm",
                                                     "rz_deg", "ry_deg", "rx_deg"};
constexpr std::array<const char*, 6> kJointColumns = {"j1", "j2", "j3", "j4", "j5", "j6"};

struct Header {
  int name = -1, config = -1;
  std::array<int, 6> values{};  // pose or joint columns, by field index
  size_t fields = 0;
};

int columnOf(const std::vector<std::string_view>& fields, const char* name) {
  for (size_t f = 0; f < fields.size(); ++f)
    if (fields[f] == name) return static_cast<int>(f);
  return -1;
}

Header readHeader(const std::vector<std::string_view>& fields, bool& joints_form,
                  const std::string& where) {
  Header h;
  h.fields = fields.size();
  int pose_found = 0, joint_found = 0;
  for (const char* c : kPoseColumns) pose_found += columnOf(fields, c) >= 0;
  for (const char* c : kJointColumns) joint_found += columnOf(fields, c) >= 0;
  if (pose_found && joint_found)
    throw FormatError(where +
                      "the header has pose columns (x_mm ...) and joint columns (j1 ...): "
                      "give one form per file");
  if (!pose_found && !joint_found)
    throw FormatError(where +
                      "the header names neither the pose columns x_mm,y_mm,z_mm,rz_deg,ry_deg,"
                      "rx_deg nor the joint columns j1,j2,j3,j4,j5,j6");
  joints_form = joint_found > 0;
  const auto& wanted = joints_form ? kJointColumns : kPoseColumns;
  for (size_t k = 0; k < wanted.size(); ++k) {
    h.values[k] = columnOf(fields, wanted[k]);
    if (h.values[k] < 0) throw FormatError(where + "the header has no column '" + wanted[k] + "'");
  }
  // compensate's own output (docs/compensation.md, "Output") read back as targets.
  if (columnOf(fields, "status") >= 0 && columnOf(fields, "predicted_error_mm") >= 0)
    throw FormatError(where +
                      "this is robocal compensate's output (its status and predicted_error_mm "
                      "columns), not a targets file: give the targets it was made from");
  h.name = columnOf(fields, "name");
  h.config = columnOf(fields, "config");
  if (h.config >= 0 && joints_form)
    throw FormatError(where + "column 'config': only for poses (joints fix the configuration)");
  for (size_t f = 0; f < fields.size(); ++f) {
    const bool known =
        static_cast<int>(f) == h.name || static_cast<int>(f) == h.config ||
        std::find(h.values.begin(), h.values.end(), static_cast<int>(f)) != h.values.end();
    if (!known)
      throw FormatError(where + "unknown column '" + std::string(fields[f]) +
                        "' (see docs/compensation.md)");
  }
  return h;
}

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

// Free text for a CSV field: the reader splits at commas and has no quoting.
std::string csvText(std::string text) {
  for (char& c : text)
    if (c == ',' || c == '\n') c = ';';
  return text;
}

}  // namespace

TargetFile parseTargets(const std::string& text, const std::string& source) {
  TargetFile file;
  file.source = source;
  std::optional<Header> header;
  csv::forEachLine(text, [&](int line_no, std::string_view line) {
    const auto fields = csv::splitFields(line);
    const std::string where = source + ":" + std::to_string(line_no) + ": ";
    if (!header) {
      header = readHeader(fields, file.joints_form, where);
      file.has_names = header->name >= 0;
      return;
    }
    if (fields.size() != header->fields)
      throw FormatError(where + "expected " + std::to_string(header->fields) + " fields, got " +
                        std::to_string(fields.size()));
    const auto& names = file.joints_form ? kJointColumns : kPoseColumns;
    std::array<double, 6> v{};
    for (size_t k = 0; k < v.size(); ++k) {
      const std::string_view field = fields[header->values[k]];
      const std::optional<double> value = csv::number(field);
      if (!value)
        throw FormatError(where + "column '" + names[k] + "': not a finite number: '" +
                          std::string(field) + "'");
      v[k] = *value;
    }
    Target t;
    t.line = line_no;
    t.written = v;
    if (header->name >= 0) t.name = std::string(fields[header->name]);
    if (file.joints_form) {
      t.nominal_joints = JointsDeg(v.data());
    } else {
      t.pose = poseFromXyzZyx(v[0], v[1], v[2], v[3], v[4], v[5]);
      if (header->config >= 0 && !fields[header->config].empty()) {
        const std::string word(fields[header->config]);
        t.config = parseArmConfig(word);
        if (!t.config)
          throw FormatError(where + "column 'config': unknown arm configuration '" + word +
                            "' (like right-up-noflip: right|left, up|down, noflip|flip)");
      }
    }
    file.targets.push_back(std::move(t));
  });
  if (!header) throw FormatError(source + ": empty: no header row (see docs/compensation.md)");
  if (file.targets.empty())
    throw FormatError(source + ": no targets: a header and no rows (see docs/compensation.md)");
  return file;
}

std::optional<std::string> targetsUnitsProblem(const TargetFile& file) {
  if (file.targets.empty()) return std::nullopt;
  const std::string first =
      " (first at " + file.source + ":" + std::to_string(file.targets.front().line) + ")";
  // The largest absolute value of the written columns [from, from + 3), over all targets.
  const auto largest = [&](int from) {
    double m = 0;
    for (const Target& t : file.targets)
      for (int k = from; k < from + 3; ++k) m = std::max(m, std::abs(t.written[k]));
    return m;
  };
  constexpr double kTurnRad = 2 * M_PI + 0.01;
  if (file.joints_form) {
    const double joints = std::max(largest(0), largest(3));
    // A program's joints sweep tens of degrees: every one within a turn in radians is radians.
    if (file.targets.size() >= 2 && joints > 0.5 && joints <= kTurnRad)
      return "every joint of these " + std::to_string(file.targets.size()) +
             " targets lies within +/-" + fixed(joints, 2) + ", as if in radians" + first +
             "; targets hold joints in degrees (docs/compensation.md): convert them (x 57.2958)";
    return std::nullopt;
  }
  // A tool a few millimetres from the fixture's origin at every target is a tool in metres.
  const double position = largest(0);
  if (position > 0.01 && position <= 3)
    return "every target position lies within " + fixed(position, 3) +
           " of the fixture's origin, as if in metres" + first +
           "; x_mm, y_mm, z_mm are millimetres: convert them (x 1000)";
  // A tool's orientations over a program span more than a few degrees (pointing down alone is
  // 90-180 about some axis): every angle within a turn in radians is radians.
  const double angle = largest(3);
  if (file.targets.size() >= 2 && angle > 0.5 && angle <= kTurnRad)
    return "every target angle lies within +/-" + fixed(angle, 2) + ", as if in radians" + first +
           "; rz_deg, ry_deg, rx_deg are degrees: convert them (x 57.2958)";
  return std::nullopt;
}

TargetFile loadTargetsFile(const std::string& path) {
  return parseTargets(readTextFile(path), path);
}

CompensatedTarget compensateTarget(const Compensator& compensator, const Target& target) {
  if (target.nominal_joints) return compensator.forNominalJoints(*target.nominal_joints);
  return compensator.forPose(*target.pose, target.config);
}

std::optional<OutputFormat> parseOutputFormat(const std::string& word) {
  if (word == "csv") return OutputFormat::kCsv;
  if (word == "val2") return OutputFormat::kVal2Points;
  if (word == "val2-move") return OutputFormat::kVal2Moves;
  if (word == "vplus-locations") return OutputFormat::kVplusLocations;
  if (word == "as-joints") return OutputFormat::kAsJoints;
  return std::nullopt;
}

namespace {

std::string predictedText(const CompensatedTarget& r) {
  return std::isnan(r.predicted_position_error_mm) ? "" : fixed(r.predicted_position_error_mm, 4);
}

// "; " + why a target is not ok, or "" when it is.
std::string statusSuffix(const CompensatedTarget& r) {
  if (r.status == CompensationStatus::kOk) return "";
  return std::string(": ") + compensationStatusName(r.status) + ": " + r.reason;
}

std::string csvOutput(const TargetFile& file, const std::vector<CompensatedTarget>& results) {
  std::string out = file.has_names ? "name," : "";
  out += "j1,j2,j3,j4,j5,j6,a1,a2,a3,a4,a5,a6,predicted_error_mm,status,config,note\n";
  for (size_t i = 0; i < results.size(); ++i) {
    const CompensatedTarget& r = results[i];
    const bool joints = r.hasJoints();
    if (file.has_names) out += file.targets[i].name + ",";
    for (int j = 0; j < kJointCount; ++j) out += (joints ? fixed(r.joints_deg[j], 10) : "") + ",";
    for (int j = 0; j < kJointCount; ++j)
      out += (joints && r.hasApproach() ? std::to_string(r.approach[j]) : "") + ",";
    out += predictedText(r) + "," + compensationStatusName(r.status) + "," +
           armConfigName(r.config) + "," + csvText(r.reason) + "\n";
  }
  return out;
}

std::string val2Output(const TargetFile& file, const std::vector<CompensatedTarget>& results,
                       bool moves) {
  std::string out;
  for (size_t i = 0; i < results.size(); ++i) {
    const CompensatedTarget& r = results[i];
    const std::string& name = file.targets[i].name;
    const std::string label = name.empty() ? "line " + std::to_string(file.targets[i].line) : name;
    // Every target named (its name, else its line in the targets file), so a person can find it;
    // one that cannot be commanded is only that comment.
    out += "; " + label + statusSuffix(r) + "\n";
    if (!r.hasJoints()) continue;
    const auto point = [&](const JointsDeg& q) {
      std::string text = moves ? "DO MOVE #PPOINT(" : "#PPOINT(";
      for (int j = 0; j < kJointCount; ++j) text += (j ? ", " : "") + fixed(q[j], 4);
      return text + ")\n";
    };
    // A points list stays one line a target (programs index it): its pre-point is a comment.
    if (r.hasApproach()) out += (moves ? "" : "; pre-point ") + point(r.pre_point_deg);
    out += point(r.joints_deg);
  }
  return out;
}

// A name a V+ or AS location takes: a letter, then letters, digits, '.' or '_'.
bool isLocationName(const std::string& name) {
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0]))) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.';
  });
}

std::string locationOutput(const TargetFile& file, const std::vector<CompensatedTarget>& results,
                           OutputFormat format) {
  const bool as = format == OutputFormat::kAsJoints;
  std::string body;
  std::set<std::string> used;
  const auto define = [&](const std::string& name, const JointsDeg& q, const Target& t) {
    if (!used.insert(name).second)
      throw FormatError(file.source + ":" + std::to_string(t.line) + ": location #" + name +
                        " would be defined twice in the " + (as ? "AS" : "V+") +
                        " location file: give each target its own name (a pre-point is "
                        "name_pre)");
    body += "#" + name;
    for (int j = 0; j < kJointCount; ++j) body += " " + fixed(q[j], 6);
    body += "\n";
  };
  for (size_t i = 0; i < results.size(); ++i) {
    const CompensatedTarget& r = results[i];
    const Target& t = file.targets[i];
    const std::string name = t.name.empty() ? "p" + std::to_string(t.line) : t.name;
    if (!isLocationName(name))
      throw FormatError(file.source + ":" + std::to_string(t.line) + ": '" + name +
                        "' is not a location name (a letter, then letters, digits, '.' or '_')");
    if (r.status != CompensationStatus::kOk) body += "; " + name + statusSuffix(r) + "\n";
    if (!r.hasJoints()) continue;
    if (r.hasApproach()) define(name + "_pre", r.pre_point_deg, t);
    define(name, r.joints_deg, t);
  }
  return std::string(as ? ".JOINTS" : ".LOCATIONS") + "\n" + body + ".END\n";
}

}  // namespace

std::string formatCompensated(const TargetFile& file, const std::vector<CompensatedTarget>& results,
                              OutputFormat format, double approach_deg) {
  if (format == OutputFormat::kCsv) return csvOutput(file, results);
  const bool locations =
      format == OutputFormat::kVplusLocations || format == OutputFormat::kAsJoints;
  std::string out = "; robocal compensate: corrected joint readings (deg) of " + file.source + "\n";
  if (approach_deg > 0)
    out += "; each target follows its approach pre-point, " + fixed(approach_deg, 4) +
           " deg below it in every joint: reach the target from there, as the calibration "
           "reached its points" +
           (format == OutputFormat::kVal2Points ? " (the pre-points are comments)"
            : locations                         ? " (a target's pre-point is name_pre)"
                                                : "") +
           "\n";
  if (locations) return out + locationOutput(file, results, format);
  return out + val2Output(file, results, format == OutputFormat::kVal2Moves);
}

}  // namespace robocal
