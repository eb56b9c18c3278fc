#include <robocal/formats/frames.hpp>
#include <robocal/kinematics/kinematics.hpp>

#include <cstdio>

namespace robocal {
namespace {

using ojson = nlohmann::ordered_json;

ojson vec(const Eigen::Vector3d& v) {
  return ojson::array({v.x(), v.y(), v.z()});
}

ojson matrixRows(const Eigen::Isometry3d& t) {
  ojson rows = ojson::array();
  for (int r = 0; r < 4; ++r) {
    ojson row = ojson::array();
    for (int c = 0; c < 4; ++c) row.push_back(t.matrix()(r, c));
    rows.push_back(row);
  }
  return rows;
}

std::string matrixComment(const char* name, const Eigen::Isometry3d& t) {
  std::string out = std::string("# ") + name + " (4x4, row-major, mm):";
  char buf[64];
  for (int r = 0; r < 3; ++r) {
    out += r ? " |" : "";
    for (int c = 0; c < 4; ++c) {
      const double v = t.matrix()(r, c);
      std::snprintf(buf, sizeof buf, " %.12g", v == 0 ? 0.0 : v);  // no "-0"
      out += buf;
    }
  }
  return out + " | 0 0 0 1\n";
}

}  // namespace

std::string dhErrorSummary(const DhTable& dh) {
  std::string parallel;
  for (int j : dh.parallel_joints)
    parallel += (parallel.empty() ? "" : ", ") + std::to_string(j) + "-" + std::to_string(j + 1);
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "joints taken as parallel: %s; against the model at %d joint vectors within the "
                "limits: position error <= %.4g mm, rotation <= %.4g deg",
                parallel.empty() ? "none" : parallel.c_str(), dh.checks, dh.max_position_error_mm,
                dh.max_rotation_error_deg);
  return buf;
}

ojson modelFramesJson(const Model& model, const DhTable& dh, const std::string& source) {
  ojson out;
  out["format"] = "robocal-frames 1";
  out["model"] = model.name;
  if (!source.empty()) out["source"] = source;
  out["units"] = {{"length", "mm"}, {"angle", "deg"}};
  // The frames are the rigid chain: a model's gravity compliance (its joints twisting under the
  // arm's weight) needs robocal's own kinematics (compensate).
  out["compliance_left_out"] = model.compliance.has_value() && model.compliance->twists();
  out["chain"] =
      "T = L0 * Rz(theta1) * L1 * ... * Rz(theta6) * L6, theta_k = offset_deg_k + gain_k * "
      "reading_k; T is the tool frame (after L6) in the global frame (the chuck fixture's)";
  ojson links = ojson::array();
  for (const LinkParams& l : model.links) {
    const Eigen::Isometry3d t = linkTransform(l);
    const Eigen::Quaterniond q(t.linear());
    links.push_back({{"name", l.name},
                     {"translation_mm", vec(t.translation())},
                     {"quaternion_wxyz", ojson::array({q.w(), q.x(), q.y(), q.z()})},
                     {"matrix", matrixRows(t)}});
  }
  out["links"] = links;
  // Each joint's axis in the global frame with every reading 0 (a rigid arm).
  const auto frames = Kinematics(toParams(model)).chainFrames(JointsDeg::Zero());
  ojson joints = ojson::array();
  for (int k = 0; k < kJointCount; ++k) {
    const JointParams& j = model.joints[k];
    joints.push_back({{"name", j.name},
                      {"offset_deg", j.offset_deg},
                      {"gain", j.gain},
                      {"min_deg", j.min_deg},
                      {"max_deg", j.max_deg},
                      {"origin_at_zero_mm", vec(frames[2 * k].translation())},
                      {"axis_at_zero", vec(frames[2 * k].linear().col(2))}});
  }
  out["joints"] = joints;
  ojson balls = ojson::array(), chucks = ojson::array();
  for (const auto& b : model.balls_mm) balls.push_back(vec(b));
  for (const auto& c : model.chucks_mm) chucks.push_back(vec(c));
  out["balls_mm"] = balls;
  out["chucks_mm"] = chucks;
  ojson rows = ojson::array();
  for (int k = 0; k < kJointCount; ++k) {
    const DHRow& r = dh.rows[k];
    rows.push_back({{"theta_offset_deg", r.theta_offset_deg},
                    {"d_mm", r.d_mm},
                    {"a_mm", r.a_mm},
                    {"alpha_deg", r.alpha_deg},
                    {"gain", dh.gains[k]}});
  }
  ojson parallel = ojson::array();
  for (int j : dh.parallel_joints) parallel.push_back(ojson::array({j, j + 1}));
  out["dh"] = {{"convention",
                "T = base * A1 * ... * A6 * tool, A_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i), "
                "theta_i = theta_offset_deg_i + gain_i * reading_i"},
               {"base", matrixRows(dh.base)},
               {"tool", matrixRows(dh.tool)},
               {"rows", rows},
               {"parallel_joints", parallel},
               {"checks", dh.checks},
               {"max_position_error_mm", dh.max_position_error_mm},
               {"max_rotation_error_deg", dh.max_rotation_error_deg}};
  return out;
}

std::string dhTableCsv(const Model& model, const DhTable& dh, const std::string& source) {
  char buf[256];
  std::string out = "# Standard DH table of " + model.name +
                    (source.empty() ? "" : " (" + source + ")") +
                    ", written by robocal export --dh\n";
  out +=
      "# T = base * A1 * ... * A6 * tool, A_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i),\n"
      "# theta_i = theta_offset_deg + gain * reading (deg); tool = the model's tool frame "
      "(balls)\n";
  out += matrixComment("base", dh.base);
  out += matrixComment("tool", dh.tool);
  out += "# " + dhErrorSummary(dh) + "\n";
  out += "joint,theta_offset_deg,d_mm,a_mm,alpha_deg,gain\n";
  for (int k = 0; k < kJointCount; ++k) {
    const DHRow& r = dh.rows[k];
    std::snprintf(buf, sizeof buf, "%d,%.9f,%.6f,%.6f,%.9f,%.9g\n", k + 1, r.theta_offset_deg,
                  r.d_mm, r.a_mm, r.alpha_deg, dh.gains[k]);
    out += buf;
  }
  return out;
}

}  // namespace robocal
