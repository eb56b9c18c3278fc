#include <robocal/formats/urdf.hpp>

#include "report_parts.hpp"

#include <robocal/build_info.hpp>
#include <robocal/kinematics/units.hpp>

#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <set>
#include <stdexcept>

namespace robocal {
namespace {

// The fewest digits that read back as the same double ("0.4318", not "0.43180000000000002"). No
// "-0"; magnitudes below 1e-300 are written as 0 (a reader may refuse a subnormal as out of range).
std::string number(double value) {
  if (std::abs(value) < 1e-300) value = 0.0;
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, value + 0.0).ptr;
  return std::string(text, end);
}

// Free text inside an XML comment: no "--" (not allowed there), no control characters, one line.
std::string commentText(const std::string& text) {
  std::string out;
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f)
      out += ' ';
    else if (c == '-' && !out.empty() && out.back() == '-')
      out += " -";
    else
      out += c;
  }
  if (!out.empty() && out.back() == '-') out += ' ';  // nor "--" with a '-' after it
  return out;
}

// Free text as an XML attribute value in double quotes: control characters become blanks.
std::string attribute(std::string text) {
  for (char& c : text)
    if (static_cast<unsigned char>(c) < 0x20) c = ' ';
  return report_detail::escapeXml(text);
}

// Fixed-axis roll, pitch, yaw of a rotation: r = Rz(yaw) * Ry(pitch) * Rx(roll). Roll is taken
// from what is left of r after yaw and pitch, so that the three reproduce r to rounding even at
// pitch = +-90 deg, where yaw and roll are not defined apart. (linkFromTransform takes both from
// atan2 of rounding noise there: linkTransform of a link with ry = 90 deg and rz, rx not 0 does
// not survive its round trip. Not fixed there: its output is the model files' numbers.)
Eigen::Vector3d rollPitchYaw(const Eigen::Matrix3d& r) {
  const double yaw = std::atan2(r(1, 0), r(0, 0));
  const double pitch = std::atan2(-r(2, 0), std::hypot(r(0, 0), r(1, 0)));
  const Eigen::Matrix3d rest = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()))
                                   .toRotationMatrix()
                                   .transpose() *
                               r;  // Rx(roll)
  const double roll = std::atan2(rest(2, 1), rest(1, 1));
  return {roll, pitch, yaw};
}

// <origin xyz="..." rpy="..."/> of a transform given in mm.
std::string origin(const Eigen::Isometry3d& t_mm) {
  const Eigen::Vector3d xyz = t_mm.translation() / 1000.0;
  const Eigen::Vector3d rpy = rollPitchYaw(t_mm.linear());
  return "<origin xyz=\"" + number(xyz.x()) + " " + number(xyz.y()) + " " + number(xyz.z()) +
         "\" rpy=\"" + number(rpy.x()) + " " + number(rpy.y()) + " " + number(rpy.z()) + "\"/>";
}

std::string translationOrigin(const Eigen::Vector3d& p_mm) {
  return "<origin xyz=\"" + number(p_mm.x() / 1000.0) + " " + number(p_mm.y() / 1000.0) + " " +
         number(p_mm.z() / 1000.0) + "\" rpy=\"0 0 0\"/>";
}

std::string fixedJoint(const std::string& name, const std::string& parent, const std::string& child,
                       const std::string& origin_element) {
  return "  <joint name=\"" + name + "\" type=\"fixed\">\n    <parent link=\"" + parent +
         "\"/>\n    <child link=\"" + child + "\"/>\n    " + origin_element + "\n  </joint>\n";
}

std::string ballLink(int b) {
  return "ball" + std::to_string(b + 1);
}
std::string chuckLink(int c) {
  return "chuck" + std::to_string(c + 1);
}
std::string bodyLink(int k /*1-based*/) {
  return "link" + std::to_string(k);
}
const char* const kBallFixtureJoint = "ball_fixture_joint";

void checkFinite(const Model& model) {
  const ParamVector params = toParams(model);
  for (int i = 0; i < kParamCount; ++i)
    if (!std::isfinite(params[i]))
      throw std::invalid_argument("modelToUrdf: " + paramName(i) + " is not a finite number");
  for (int j = 0; j < kJointCount; ++j) {
    const JointParams& joint = model.joints[j];
    if (joint.gain == 0.0)
      throw std::invalid_argument("modelToUrdf: J" + std::to_string(j + 1) + ".gain is zero");
    if (!std::isfinite(joint.min_deg) || !std::isfinite(joint.max_deg))
      throw std::invalid_argument("modelToUrdf: J" + std::to_string(j + 1) +
                                  " limits are not finite numbers");
  }
  for (int b = 0; b < kBallCount; ++b)
    if (!model.balls_mm[b].allFinite())
      throw std::invalid_argument("modelToUrdf: balls[" + std::to_string(b) +
                                  "] is not a finite point");
  for (int c = 0; c < kChuckCount; ++c)
    if (!model.chucks_mm[c].allFinite())
      throw std::invalid_argument("modelToUrdf: chucks[" + std::to_string(c) +
                                  "] is not a finite point");
}

std::string provenanceLines(const Model& model) {
  if (!model.provenance)
    return "  Provenance: none recorded (a nominal model, or a file older than provenance).\n";
  const ModelProvenance& p = *model.provenance;
  std::string out = "  Provenance: fitted " + commentText(p.date_utc);
  if (!p.run_id.empty()) out += " (robocald run " + commentText(p.run_id) + ")";
  out += " by robocal " + commentText(p.robocal_version) + "\n";
  out += "    from the model: " + commentText(p.nominal_name) + "\n";
  out += "    " + std::to_string(p.samples) + " samples, RMS residual " + number(p.rms_mm) +
         " mm, rank " + std::to_string(p.rank) + " of " + std::to_string(p.expected_rank) + "\n";
  for (const std::string& f : p.samples_files) out += "    samples: " + commentText(f) + "\n";
  for (const std::string& w : p.warnings) out += "    fit warning: " + commentText(w) + "\n";
  return out;
}

std::string headerComment(const Model& model, const UrdfOptions& options,
                          const std::array<std::string, kJointCount>& joints) {
  bool unit_gains = true;
  for (const JointParams& j : model.joints) unit_gains = unit_gains && j.gain == 1.0;
  std::string out = "<!--\n";
  out += std::string("  URDF of a robocal model, written by robocal ") + build::kVersion +
         " (robocal export; docs/export.md).\n";
  out += "  Model: " + commentText(model.name) + "\n";
  if (!options.source.empty()) out += "  Source: " + commentText(options.source) + "\n";
  out += provenanceLines(model);
  out +=
      "\n"
      "  Frames: chuck_fixture (the root) is the model's global frame, the chuck fixture's; the\n"
      "  chucks chuck1..chuck3 are fixed to it at their centres. link1..link6 are the frames of\n"
      "  joints 1..6, each turning about its own z axis. ball_fixture is the frame after the last\n"
      "  link transform L6, in which the model gives the tool balls ball1..ball3 (fixed to it at\n"
      "  their centres). Joint k's origin is L(k-1) * Rz(offset k) of the model\n"
      "  (T = L0 * J1 * L1 * ... * J6 * L6, Jk = Rz(offset k + gain k * reading k)).\n"
      "  Units: meters and radians (the model file's mm and degrees converted); rpy is fixed-axis\n"
      "  roll, pitch, yaw: R = Rz(yaw) * Ry(pitch) * Rx(roll).\n"
      "  Limits: the controller's reading limits (the model's min and max) in radians. Velocity\n"
      "  (rad/s) and effort (N m): the model's joints' velocity_deg_per_s and effort_nm, or where\n"
      "  the model has none the values the export was given (below).\n"
      "\n"
      "  Joint gains (URDF cannot hold a gain): each joint's URDF value must be\n"
      "  gain * reading, the controller's reading in radians times the gain below.\n";
  for (int j = 0; j < kJointCount; ++j)
    out += "    " + commentText(joints[j]) + " gain " + number(model.joints[j].gain) +
           (model.joints[j].gain == 1.0 ? "" : "   (not 1)") + "\n";
  bool velocity_given = false, effort_given = false;
  for (const JointParams& j : model.joints) {
    velocity_given = velocity_given || !(j.velocity_deg_per_s > 0);
    effort_given = effort_given || !(j.effort_nm > 0);
  }
  if (velocity_given)
    out += "  Velocity given to the export, for the joints the model has none of: " +
           number(options.velocity_deg_per_s) + " deg/s.\n";
  if (effort_given)
    out += "  Effort given to the export, for the joints the model has none of: " +
           number(options.effort_nm) + " N m.\n";
  if (model.compliance && model.compliance->twists())
    out +=
        "  Gravity compliance (URDF cannot hold it): the model's joints twist under gravity by\n"
        "  compliance * torque (docs/model-format.md, \"Compliance\"); this URDF is the rigid\n"
        "  arm, off by that twist: evaluate the model file with robocal for the loaded arm.\n";
  if (unit_gains)
    out += "  Every gain is 1: the URDF joint value is the controller's reading in radians.\n";
  else
    out +=
        "  Some gains are not 1: for exact forward kinematics set those joints' values to\n"
        "  reading * gain; the reading alone turns them by (gain - 1) * reading too little or\n"
        "  too much.\n";
  out +=
      "  The exact path stays robocal's own: corrected joint targets come from\n"
      "  `robocal compensate` with the model file (docs/compensation.md). This URDF reproduces\n"
      "  the model to rounding only with those joint values.\n"
      "-->\n";
  return out;
}

}  // namespace

std::string urdfRobotName(const Model& model) {
  std::string out;
  for (const char c : model.name) {
    if (std::isalnum(static_cast<unsigned char>(c)) && static_cast<unsigned char>(c) < 0x80)
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    else if (!out.empty() && out.back() != '_')
      out += '_';
  }
  while (!out.empty() && out.back() == '_') out.pop_back();
  return out.empty() ? "robot" : out;
}

std::array<std::string, kJointCount> urdfJointNames(const Model& model) {
  std::set<std::string> taken = {kBallFixtureJoint};
  for (int b = 0; b < kBallCount; ++b) taken.insert(ballLink(b) + "_joint");
  for (int c = 0; c < kChuckCount; ++c) taken.insert(chuckLink(c) + "_joint");
  std::array<std::string, kJointCount> names;
  bool usable = true;
  for (int j = 0; j < kJointCount; ++j) {
    names[j] = model.joints[j].name;
    usable = usable && !names[j].empty() && taken.insert(names[j]).second;
  }
  if (!usable)
    for (int j = 0; j < kJointCount; ++j) names[j] = "J" + std::to_string(j + 1);
  return names;
}

std::array<UrdfJointLimits, kJointCount> urdfLimits(const Model& model, const UrdfOptions& options,
                                                    std::string* missing) {
  const auto names = urdfJointNames(model);
  std::array<UrdfJointLimits, kJointCount> out;
  for (int j = 0; j < kJointCount; ++j) {
    const JointParams& joint = model.joints[j];
    out[j].velocity_deg_per_s =
        joint.velocity_deg_per_s > 0 ? joint.velocity_deg_per_s : options.velocity_deg_per_s;
    out[j].effort_nm = joint.effort_nm > 0 ? joint.effort_nm : options.effort_nm;
    for (const auto& [value, what] : {std::pair{out[j].velocity_deg_per_s, " velocity"},
                                      std::pair{out[j].effort_nm, " effort"}})
      if (missing && !(value > 0)) *missing += (missing->empty() ? "" : ", ") + names[j] + what;
  }
  return out;
}

std::string modelToUrdf(const Model& model, const UrdfOptions& options) {
  checkFinite(model);
  std::string missing;
  const auto limits = urdfLimits(model, options, &missing);
  if (!missing.empty()) {
    throw std::invalid_argument(
        "URDF needs each joint's velocity and effort, and the model has none for: " + missing +
        " (joints[].velocity_deg_per_s and effort_nm in the model file, or given to the export)");
  }
  const std::array<std::string, kJointCount> joints = urdfJointNames(model);
  const std::string robot = options.robot_name.empty() ? urdfRobotName(model) : options.robot_name;

  std::string out = "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n";
  out += headerComment(model, options, joints);
  out += "<robot name=\"" + attribute(robot) + "\">\n";
  out += "  <link name=\"" + std::string(kUrdfBaseLink) + "\"/>\n";
  for (int k = 1; k <= kJointCount; ++k) out += "  <link name=\"" + bodyLink(k) + "\"/>\n";
  out += "  <link name=\"" + std::string(kUrdfBallFixtureLink) + "\"/>\n";
  for (int b = 0; b < kBallCount; ++b) out += "  <link name=\"" + ballLink(b) + "\"/>\n";
  for (int c = 0; c < kChuckCount; ++c) out += "  <link name=\"" + chuckLink(c) + "\"/>\n";

  for (int j = 0; j < kJointCount; ++j) {
    const JointParams& joint = model.joints[j];
    const Eigen::Isometry3d place =
        linkTransform(model.links[j]) *
        Eigen::AngleAxisd(degToRad(joint.offset_deg), Eigen::Vector3d::UnitZ());
    out += "  <joint name=\"" + attribute(joints[j]) + "\" type=\"revolute\">\n";
    out += "    <parent link=\"" + (j == 0 ? std::string(kUrdfBaseLink) : bodyLink(j)) + "\"/>\n";
    out += "    <child link=\"" + bodyLink(j + 1) + "\"/>\n";
    out += "    " + origin(place) + "\n";
    out += "    <axis xyz=\"0 0 1\"/>\n";
    out += "    <limit lower=\"" + number(degToRad(joint.min_deg)) + "\" upper=\"" +
           number(degToRad(joint.max_deg)) + "\" effort=\"" + number(limits[j].effort_nm) +
           "\" velocity=\"" + number(degToRad(limits[j].velocity_deg_per_s)) + "\"/>\n";
    out += "  </joint>\n";
  }
  out += fixedJoint(kBallFixtureJoint, bodyLink(kJointCount), kUrdfBallFixtureLink,
                    origin(linkTransform(model.links[kLinkCount - 1])));
  for (int b = 0; b < kBallCount; ++b)
    out += fixedJoint(ballLink(b) + "_joint", kUrdfBallFixtureLink, ballLink(b),
                      translationOrigin(model.balls_mm[b]));
  for (int c = 0; c < kChuckCount; ++c)
    out += fixedJoint(chuckLink(c) + "_joint", kUrdfBaseLink, chuckLink(c),
                      translationOrigin(model.chucks_mm[c]));
  out += "</robot>\n";
  return out;
}

}  // namespace robocal
