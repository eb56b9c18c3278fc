// The URDF import (formats/include/robocal/formats/urdf_import.hpp): a serial chain read by
// urdfdom becomes a model whose forward kinematics are the URDF's, composed independently from
// the parsed joints (urdf_fk.hpp); robocal's own export comes back as the same arm.
#include <catch2/catch.hpp>

#include <robocal/formats/error.hpp>
#include <robocal/formats/urdf.hpp>
#include <robocal/formats/urdf_import.hpp>
#include <robocal/kinematics/units.hpp>

#include "urdf_fk.hpp"

#include <regex>

using namespace robocal;
using namespace robocal::test;
using Catch::Matchers::Contains;

namespace {

// A UR5 as ROS-Industrial's ur_description describes it (config/ur5.urdf says more): joints
// about y and z, a world link above the base, and two fixed frames on the flange (the chain
// branches after the sixth joint).
const std::string kUr5 = readTextFile(ROBOCAL_SOURCE_DIR "/config/ur5.urdf");

// The worst difference over `poses` random readings between the model's tool pose and the pose
// of `tip` relative to `base` composed from the parsed URDF's joints.
struct Worst {
  double mm = 0, rad = 0;
};
Worst compareTip(const Model& m, const std::string& urdf_text, const std::string& base,
                 const std::string& tip, int poses, unsigned seed) {
  const auto urdf = parse(urdf_text);
  const Kinematics kin(m);
  std::mt19937_64 rng(seed);
  Worst w;
  for (int n = 0; n < poses; ++n) {
    const JointsDeg q = randomReadings(m, rng);
    std::map<std::string, double> values;
    for (int j = 0; j < kJointCount; ++j) values[m.joints[j].name] = degToRad(q[j]);
    const auto links = linkPoses(*urdf, values);
    Eigen::Isometry3d expected = links.at(base).inverse() * links.at(tip);
    expected.translation() *= 1000.0;
    const Eigen::Isometry3d got = kin.toolPose(q);
    w.mm = std::max(w.mm, (got.translation() - expected.translation()).norm());
    w.rad = std::max(w.rad, angleBetween(got.linear(), expected.linear()));
  }
  return w;
}

std::string replaced(const std::string& text, const std::string& from, const std::string& to) {
  return std::regex_replace(text, std::regex(from), to);
}

}  // namespace

TEST_CASE(
    "a UR5's URDF imported: its joints about y and z, the model's kinematics are the URDF's") {
  const UrdfImport imported = urdfToModel(kUr5, "ur5.urdf");
  const Model& m = imported.model;
  CHECK(m.name == "ur5 (URDF)");
  CHECK(imported.base_link == "world");
  CHECK(imported.tip_link == "wrist_3_link");  // where the chain branches into two flange frames
  CHECK(imported.fixed_joints == std::vector<std::string>{"world_joint"});
  CHECK_FALSE(imported.fixtures_found);
  CHECK(m.joints[0].name == "shoulder_pan_joint");
  CHECK(m.joints[5].name == "wrist_3_joint");
  CHECK(m.joints[2].min_deg == Approx(-180.0).epsilon(1e-8));
  CHECK(m.joints[5].max_deg == 360.0);  // continuous
  // The rated speed and torque: 3.15 rad/s, 150 N m on the shoulder; none on the continuous
  // wrist 3 (no <limit>).
  CHECK(m.joints[1].velocity_deg_per_s == Approx(3.15 * 180 / M_PI));
  CHECK(m.joints[1].effort_nm == 150.0);
  CHECK(m.joints[5].velocity_deg_per_s == 0);
  // Every link's ZYX angles away from ry = +-90 deg, where rz and rx turn about one axis (the
  // UR's axes along y would put its shoulder link there).
  for (int k = 0; k < kJointCount; ++k) CHECK(std::abs(m.links[k].ry_deg) < 1e-9);
  for (const JointParams& j : m.joints) {
    CHECK(j.offset_deg == 0);
    CHECK(j.gain == 1);
  }
  // 1,000 joint vectors over the limits: the tool pose within 1 nm and 1e-9 rad.
  const Worst w = compareTip(m, kUr5, "world", "wrist_3_link", 1000, 1);
  CAPTURE(w.mm, w.rad);
  CHECK(w.mm <= kPositionTolMm);
  CHECK(w.rad <= kAngleTolRad);

  // Another tip and base: the flange frame tool0, from base_link.
  UrdfImportOptions options;
  options.base_link = "base_link";
  options.tip_link = "tool0";
  const UrdfImport to_tool = urdfToModel(kUr5, "ur5.urdf", options);
  CHECK(to_tool.fixed_joints == std::vector<std::string>{"wrist_3_link-tool0_fixed_joint"});
  const Worst t = compareTip(to_tool.model, kUr5, "base_link", "tool0", 1000, 2);
  CAPTURE(t.mm, t.rad);
  CHECK(t.mm <= kPositionTolMm);
  CHECK(t.rad <= kAngleTolRad);
}

TEST_CASE("axes along -z, along a slant, and not of unit length come in as the URDF turns them") {
  std::string text = replaced(kUr5, R"(<axis xyz="0 0 1"/>)", R"(<axis xyz="0 0 -1"/>)");
  text = replaced(text, R"(<axis xyz="0 1 0"/>)", R"(<axis xyz="0.3 2 -0.5"/>)");
  const UrdfImport imported = urdfToModel(text, "slanted.urdf");
  const Worst w = compareTip(imported.model, text, "world", "wrist_3_link", 1000, 3);
  CAPTURE(w.mm, w.rad);
  CHECK(w.mm <= kPositionTolMm);
  CHECK(w.rad <= kAngleTolRad);
}

TEST_CASE("robocal's own URDF export comes back as the same arm, balls and chucks included") {
  std::mt19937_64 rng(7);
  for (int n = 0; n < 10; ++n) {
    const Model original = calibratedLike(rng);
    const std::string text = modelToUrdf(original);
    const UrdfImport back = urdfToModel(text, "export.urdf");
    CHECK(back.base_link == kUrdfBaseLink);
    CHECK(back.tip_link == kUrdfBallFixtureLink);
    REQUIRE(back.fixtures_found);
    const Kinematics a(original), b(back.model);
    for (int k = 0; k < 50; ++k) {
      const JointsDeg q = randomReadings(original, rng);
      CHECK((a.toolPose(q).translation() - b.toolPose(q).translation()).norm() <= kPositionTolMm);
      CHECK(angleBetween(a.toolPose(q).linear(), b.toolPose(q).linear()) <= kAngleTolRad);
    }
    for (int i = 0; i < kBallCount; ++i) {
      CHECK((back.model.balls_mm[i] - original.balls_mm[i]).norm() <= kPositionTolMm);
      CHECK((back.model.chucks_mm[i] - original.chucks_mm[i]).norm() <= kPositionTolMm);
    }
    for (int j = 0; j < kJointCount; ++j) {
      CHECK(back.model.joints[j].name == original.joints[j].name);
      CHECK(back.model.joints[j].min_deg == Approx(original.joints[j].min_deg).epsilon(1e-12));
      CHECK(back.model.joints[j].max_deg == Approx(original.joints[j].max_deg).epsilon(1e-12));
    }
  }
}

TEST_CASE("a URDF robocal cannot model is refused, naming the joint or link") {
  const auto refused = [](const std::string& text, const std::string& what,
                          const UrdfImportOptions& options = {}) {
    CHECK_THROWS_WITH(urdfToModel(text, "arm.urdf", options),
                      Contains("arm.urdf: ") && Contains(what));
  };
  refused(replaced(kUr5, R"(name="elbow_joint" type="revolute")",
                   R"(name="elbow_joint" type="prismatic")"),
          "joint 'elbow_joint' is prismatic");
  // Five joints: wrist 3 fixed.
  refused(replaced(kUr5, R"(name="wrist_3_joint" type="continuous")",
                   R"(name="wrist_3_joint" type="fixed")"),
          "only 5 movable joints below link 'world'");
  UrdfImportOptions options;
  options.tip_link = "wrist_2_link";
  refused(kUr5, "5 movable joints from 'world' to 'wrist_2_link'", options);
  options.tip_link = "tool0";
  options.base_link = "forearm_link";
  refused(kUr5, "3 movable joints", options);
  options.base_link = "tool0";
  options.tip_link = "base_link";
  refused(kUr5, "link 'tool0' is not above link 'base_link'", options);
  options.base_link = "no_such_link";
  refused(kUr5, "no link named 'no_such_link' (--base)", options);
  refused(replaced(kUr5, R"(<axis xyz="0 0 1"/>)", R"(<axis xyz="0 0 1"/><mimic joint="x"/>)"),
          "mimics another");
  refused(replaced(kUr5, R"(lower="-3.14159265" upper="3.14159265")",
                   R"(lower="3.14159265" upper="-3.14159265")"),
          "joint 'elbow_joint': expected finite limits, the lower below the upper");
  refused(replaced(kUr5, R"(effort="150" velocity="3.15")", R"(effort="150" velocity="3150")"),
          "joint 'shoulder_pan_joint': velocity past");
  CHECK_THROWS_WITH(urdfToModel("<robot", "broken.urdf"),
                    Contains("broken.urdf: not a URDF that urdfdom can read"));
}

TEST_CASE(
    "a URDF's other shapes robocal cannot model: floating, planar, seven joints, a branch, "
    "a missing link, a loop") {
  const auto refused = [](const std::string& text, const std::string& what,
                          const UrdfImportOptions& options = {}) {
    CHECK_THROWS_WITH(urdfToModel(text, "arm.urdf", options),
                      Contains("arm.urdf: ") && Contains(what));
  };
  for (const std::string type : {"floating", "planar"})
    refused(replaced(kUr5, R"(name="elbow_joint" type="revolute")",
                     "name=\"elbow_joint\" type=\"" + type + "\""),
            "joint 'elbow_joint' is " + type);
  // A seventh joint past the wrist: the flange's fixed frame made revolute, the tip below it.
  const std::string seven =
      replaced(kUr5, R"(<joint name="ee_fixed_joint" type="fixed">)",
               R"(<joint name="ee_fixed_joint" type="continuous"><axis xyz="0 0 1"/>)");
  UrdfImportOptions to_ee;
  to_ee.tip_link = "ee_link";
  refused(seven,
          "more than six movable joints from 'world' to 'ee_link' (the seventh: "
          "'ee_fixed_joint')",
          to_ee);
  // A second movable joint out of the shoulder (a second arm on the same base).
  const std::string branch = replaced(kUr5, R"(<link name="shoulder_link"/>)",
                                      R"(<link name="shoulder_link"/><link name="other_arm"/>
  <joint name="other_joint" type="continuous"><parent link="shoulder_link"/>
    <child link="other_arm"/><axis xyz="0 0 1"/></joint>)");
  refused(branch, "the chain branches at link 'shoulder_link'");
  refused(branch, "'other_joint'");
  refused(branch, "'shoulder_lift_joint'");
  refused(branch, "say where it ends with --tip LINK");
  // With the tip named, the branch is not in the way.
  UrdfImportOptions to_tool;
  to_tool.tip_link = "tool0";
  CHECK(urdfToModel(branch, "arm.urdf", to_tool).tip_link == "tool0");
  // A joint to a link that is not declared: urdfdom refuses it while parsing.
  refused(replaced(kUr5, R"(<link name="forearm_link"/>)", ""), "not a URDF that urdfdom can read");
  // A joint from the flange back to the shoulder closes a loop, which urdfdom reads.
  refused(replaced(kUr5, R"(<link name="tool0"/>)",
                   R"(<link name="tool0"/><joint name="back" type="fixed"><parent link="tool0"/>
    <child link="shoulder_link"/></joint>)"),
          "link 'shoulder_link' is the child of two joints");
}
