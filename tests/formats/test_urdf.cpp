// The URDF export (formats/include/robocal/formats/urdf.hpp) read back by a real URDF parser,
// urdfdom: its forward kinematics, composed from the parsed joints alone, are the model's.
#include <catch2/catch.hpp>

#include <robocal/formats/error.hpp>
#include <robocal/formats/urdf.hpp>
#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/units.hpp>
#include <robocal/robot/puma560.hpp>

#include "urdf_fk.hpp"

#include <urdf_parser/urdf_parser.h>

#include <stdlib.h>
#include <filesystem>
#include <functional>
#include <map>
#include <random>

using namespace robocal;
using namespace robocal::test;
using Catch::Matchers::Contains;

namespace {

struct Worst {
  double tool_mm = 0, tool_rad = 0, ball_mm = 0, chuck_mm = 0;
};

// Compares the parsed URDF's forward kinematics, with joint values gain * reading (radians; the
// reading alone when `with_gains` is false), with robocal's at `poses` random readings; returns
// the worst differences.
Worst compare(const Model& m, const urdf::ModelInterface& model, std::mt19937_64& rng, int poses,
              bool with_gains = true) {
  const Kinematics kin(m);
  const auto names = urdfJointNames(m);
  Worst worst;
  for (int n = 0; n < poses; ++n) {
    const JointsDeg q = randomReadings(m, rng);
    std::map<std::string, double> values;
    for (int j = 0; j < kJointCount; ++j)
      values[names[j]] = (with_gains ? m.joints[j].gain : 1.0) * degToRad(q[j]);
    const auto links = linkPoses(model, values);
    REQUIRE(links.size() == 1 + kJointCount + 1 + kBallCount + kChuckCount);
    const Eigen::Isometry3d tool = kin.toolPose(q);
    const Eigen::Isometry3d urdf_tool = links.at(kUrdfBallFixtureLink);
    worst.tool_mm =
        std::max(worst.tool_mm, (1000.0 * urdf_tool.translation() - tool.translation()).norm());
    worst.tool_rad = std::max(worst.tool_rad, angleBetween(urdf_tool.linear(), tool.linear()));
    for (int b = 0; b < kBallCount; ++b)
      worst.ball_mm =
          std::max(worst.ball_mm, (1000.0 * links.at("ball" + std::to_string(b + 1)).translation() -
                                   kin.ballPosition(q, m.balls_mm[b]))
                                      .norm());
    for (int c = 0; c < kChuckCount; ++c)
      worst.chuck_mm = std::max(
          worst.chuck_mm,
          (1000.0 * links.at("chuck" + std::to_string(c + 1)).translation() - m.chucks_mm[c])
              .norm());
  }
  return worst;
}

Worst compare(const Model& m, const std::string& text, std::mt19937_64& rng, int poses,
              bool with_gains = true) {
  return compare(m, *parse(text), rng, poses, with_gains);
}

void checkWorst(const Worst& w) {
  CAPTURE(w.tool_mm, w.tool_rad, w.ball_mm, w.chuck_mm);
  CHECK(w.tool_mm <= kPositionTolMm);
  CHECK(w.tool_rad <= kAngleTolRad);
  CHECK(w.ball_mm <= kPositionTolMm);
  CHECK(w.chuck_mm <= kPositionTolMm);
}

std::string headerComment(const std::string& text) {
  const size_t begin = text.find("<!--");
  const size_t end = text.find("-->");
  REQUIRE(begin != std::string::npos);
  REQUIRE(end != std::string::npos);
  REQUIRE(begin < text.find("<robot"));
  return text.substr(begin + 4, end - begin - 4);
}

}  // namespace

TEST_CASE("urdfdom reads the URDF of a calibrated-like model with robocal's forward kinematics") {
  char dir_template[] = "/tmp/robocal-urdf-XXXXXX";
  const std::filesystem::path dir = ::mkdtemp(dir_template);
  std::mt19937_64 rng(12);
  for (int trial = 0; trial < 20; ++trial) {
    const Model m = calibratedLike(rng);
    INFO("trial " << trial);
    // Written as the command writes it, and read from the file.
    const std::string path = (dir / "robot.urdf").string();
    writeTextFileAtomic(path, modelToUrdf(m));
    const urdf::ModelInterfaceSharedPtr model = urdf::parseURDFFile(path);
    REQUIRE(model);
    checkWorst(compare(m, *model, rng, 50));
  }
  std::filesystem::remove_all(dir);
}

TEST_CASE("the URDF's joints are the model's: names, chain, axis and reading limits") {
  std::mt19937_64 rng(4);
  const Model m = calibratedLike(rng);
  const urdf::ModelInterfaceSharedPtr model = parse(modelToUrdf(m));
  CHECK(model->getName() == "puma_560_calibrated_like");
  CHECK(model->getRoot()->name == kUrdfBaseLink);
  std::string parent = kUrdfBaseLink;
  for (int j = 0; j < kJointCount; ++j) {
    const urdf::JointConstSharedPtr joint = model->getJoint(m.joints[j].name);
    REQUIRE(joint);
    CHECK(joint->type == urdf::Joint::REVOLUTE);
    CHECK(joint->parent_link_name == parent);
    CHECK(joint->child_link_name == "link" + std::to_string(j + 1));
    CHECK((joint->axis.x == 0 && joint->axis.y == 0 && joint->axis.z == 1));
    REQUIRE(joint->limits);
    CHECK(joint->limits->lower == degToRad(m.joints[j].min_deg));  // exactly: shortest round trip
    CHECK(joint->limits->upper == degToRad(m.joints[j].max_deg));
    parent = joint->child_link_name;
  }
  const urdf::JointConstSharedPtr tool = model->getJoint("ball_fixture_joint");
  REQUIRE(tool);
  CHECK(tool->type == urdf::Joint::FIXED);
  CHECK(tool->parent_link_name == "link6");
  CHECK(tool->child_link_name == kUrdfBallFixtureLink);
  for (const char* ball : {"ball1", "ball2", "ball3"})
    CHECK(model->getLink(ball)->getParent()->name == kUrdfBallFixtureLink);
  for (const char* chuck : {"chuck1", "chuck2", "chuck3"})
    CHECK(model->getLink(chuck)->getParent()->name == kUrdfBaseLink);
}

TEST_CASE("the nominal PUMA's URDF reads as its numbers: meters, radians, short decimals") {
  const std::string text = modelToUrdf(rated(puma560NominalModel()), {"puma560", ""});
  CHECK_THAT(text, Contains("<robot name=\"puma560\">"));
  // J1: L0 = Trans(-550, 0, 400) mm; J2: L1 = Rx(90 deg).
  CHECK_THAT(text, Contains("<origin xyz=\"-0.55 0 0.4\" rpy=\"0 0 0\"/>"));
  // (pi/2 to the last digit or two: linkTransform's rotation is exact to rounding, not Rx(90 deg)
  // itself.)
  CHECK_THAT(text, Contains("<origin xyz=\"0 0 0\" rpy=\"1.57079632679489"));
  CHECK_THAT(text, Contains("<origin xyz=\"0.4318 0 0\" rpy=\"0 0 0\"/>"));
  CHECK_THAT(text, Contains("<limit lower=\"-2.792526803190927\" upper=\"2.792526803190927\" "
                            "effort=\"100\" velocity=\"1.5707963267948966\"/>"));
  std::mt19937_64 rng(2);
  checkWorst(compare(rated(puma560NominalModel()), text, rng, 50));
}

TEST_CASE("origins at rpy's gimbal lock (pitch +-90 deg) export exactly") {
  // There roll and yaw are not defined apart, and atan2 of rounding noise gives them.
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> angle(-179.0, 179.0);
  for (int trial = 0; trial < 20; ++trial) {
    Model m = calibratedLike(rng);
    // A base and a tool turned by 90 deg about y, and a middle link too.
    for (const int k : {0, 3, 6}) {
      m.links[k].ry_deg = trial % 2 ? 90.0 : -90.0;
      m.links[k].rz_deg = angle(rng);
      m.links[k].rx_deg = angle(rng);
    }
    // The PUMA's 90 deg twists (Rx(+-90) of L1, L4 and L5; L3 is turned above) followed by
    // offsets of +-90 deg: Rx * Rz has pitch +-90.
    for (const int j : {1, 4, 5}) {
      m.links[j].rz_deg = m.links[j].ry_deg = 0.0;
      m.joints[j].offset_deg = trial % 3 ? 90.0 : -90.0;
    }
    INFO("trial " << trial);
    checkWorst(compare(m, modelToUrdf(m), rng, 20));
  }
}

TEST_CASE("with gains other than 1 the URDF is exact when its joint values are reading * gain") {
  std::mt19937_64 rng(21);
  Model m = calibratedLike(rng);
  const std::array<double, kJointCount> gains = {1.000728, 0.99931, 1.0, 1.0012, 0.9989, 1.0};
  for (int j = 0; j < kJointCount; ++j) m.joints[j].gain = gains[j];
  const std::string text = modelToUrdf(m);
  checkWorst(compare(m, text, rng, 50));

  // With the reading alone the pose is off: what the comment warns about.
  const Worst off = compare(m, text, rng, 20, false);
  CHECK(off.ball_mm > 0.1);
}

TEST_CASE("the comment at the top states the gains, frames, units and where the model came from") {
  Model m = rated(puma560NominalModel());
  m.joints[1].gain = 1.000728;
  m.joints[4].gain = 0.9993;
  m.name = "PUMA 560 calibrated 2026-12-02";
  ModelProvenance p;
  p.run_id = "20261202-004925";
  p.date_utc = "2026-12-02T00:49:25Z";
  p.nominal_name = "PUMA 560 nominal";
  p.samples_files = {"/var/lib/robocald/runs/20261202-004925/samples.csv"};
  p.samples = 787;
  p.rms_mm = 0.0772;
  p.rank = 36;
  p.expected_rank = 36;
  p.robocal_version = "0.1.0";
  p.warnings = {"the predicted error is above the nominal's"};
  m.provenance = p;
  const std::string text = modelToUrdf(m, {"", "/models/calibrated.json"});
  const std::string comment = headerComment(text);
  CHECK(text.rfind("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<!--", 0) == 0);
  CHECK_THAT(comment, Contains("\n  Model: PUMA 560 calibrated 2026-12-02\n"));
  CHECK_THAT(comment, Contains("Source: /models/calibrated.json"));
  CHECK_THAT(comment, Contains("Provenance: fitted 2026-12-02T00:49:25Z (robocald run "
                               "20261202-004925) by robocal 0.1.0\n    from the model: PUMA 560 "
                               "nominal\n") &&
                          Contains("787 samples") && Contains("RMS residual 0.0772 mm") &&
                          Contains("rank 36 of 36") &&
                          Contains("samples: /var/lib/robocald/runs/20261202-004925/samples.csv") &&
                          Contains("fit warning: the predicted error is above the nominal's\n"));
  CHECK_THAT(comment, Contains("    J1 gain 1\n    J2 gain 1.000728   (not 1)\n    J3 gain 1\n"
                               "    J4 gain 1\n    J5 gain 0.9993   (not 1)\n    J6 gain 1\n"));
  CHECK_THAT(comment, Contains("Some gains are not 1: for exact forward kinematics set those "
                               "joints' values to\n  reading * gain"));
  CHECK_THAT(comment, Contains("Units: meters and radians") &&
                          Contains("R = Rz(yaw) * Ry(pitch) * Rx(roll)") &&
                          Contains("chuck_fixture (the root) is the model's global frame") &&
                          Contains("ball_fixture is the frame after the last") &&
                          Contains("L(k-1) * Rz(offset k)") && Contains("exact path"));

  const std::string nominal = headerComment(modelToUrdf(rated(puma560NominalModel())));
  CHECK_THAT(nominal, Contains("Every gain is 1: the URDF joint value is the controller's "
                               "reading in radians."));
  CHECK_THAT(nominal, Contains("Provenance: none recorded"));
  CHECK(nominal.find("(not 1)") == std::string::npos);
}

TEST_CASE("free text cannot break the URDF: names in the comment and the robot attribute") {
  Model m = rated(puma560NominalModel());
  m.name = "bad -- name <&> \"quoted\"\nsecond line -";
  m.joints[0].name = "J1 --";
  const std::string text = modelToUrdf(m, {"robot \"<&>\"", "/tmp/a--b.json"});
  // "--" may not appear inside an XML comment.
  CHECK(headerComment(text).find("--") == std::string::npos);
  const urdf::ModelInterfaceSharedPtr model = parse(text);
  CHECK(model->getName() == "robot \"<&>\"");
  CHECK(model->getJoint("J1 --"));
  CHECK(urdfRobotName(m) == "bad_name_quoted_second_line");
}

TEST_CASE("joint names: the model's when they are usable, J1..J6 otherwise") {
  Model m = rated(puma560NominalModel());
  const std::array<std::string, kJointCount> named = {"waist",      "shoulder",    "elbow",
                                                      "wrist_roll", "wrist_pitch", "flange"};
  for (int j = 0; j < kJointCount; ++j) m.joints[j].name = named[j];
  CHECK(urdfJointNames(m) == named);
  CHECK(parse(modelToUrdf(m))->getJoint("wrist_pitch"));
  m.joints[3].name = m.joints[2].name;  // two joints with one name
  CHECK(urdfJointNames(m) ==
        std::array<std::string, kJointCount>{"J1", "J2", "J3", "J4", "J5", "J6"});
  m = rated(puma560NominalModel());
  m.joints[0].name = "";
  CHECK(urdfJointNames(m)[0] == "J1");
  m.joints[0].name = "ball1_joint";  // a fixed joint's name
  CHECK(urdfJointNames(m)[0] == "J1");
  CHECK(parse(modelToUrdf(m))->getJoint("J1"));
}

TEST_CASE("the robot name from the model's name") {
  Model m;
  m.name = "PUMA 560 nominal (Lloyd DH), robocal reference cell";
  CHECK(urdfRobotName(m) == "puma_560_nominal_lloyd_dh_robocal_reference_cell");
  m.name = "  ()  ";
  CHECK(urdfRobotName(m) == "robot");
  m.name = "";
  CHECK(urdfRobotName(m) == "robot");
}

TEST_CASE("a model with a non-finite parameter is refused, naming the parameter") {
  Model m = rated(puma560NominalModel());
  m.links[2].ry_deg = std::nan("");
  CHECK_THROWS_WITH(modelToUrdf(m), Contains("L2.ry is not a finite number"));
  m = rated(puma560NominalModel());
  m.balls_mm[1].x() = INFINITY;
  CHECK_THROWS_WITH(modelToUrdf(m), Contains("balls[1] is not a finite point"));
}

TEST_CASE(
    "URDF limits are never 0: the model's speed and torque, else the export's, else refused") {
  Model m = puma560NominalModel();  // the shipped PUMA states no rated speed or torque
  CHECK_THROWS_WITH(modelToUrdf(m),
                    Contains("URDF needs each joint's velocity and effort, and the model has none "
                             "for: J1 velocity, J1 effort, J2 velocity"));
  m.joints[0].velocity_deg_per_s = 180.0;
  m.joints[0].effort_nm = 120.0;
  UrdfOptions options;
  options.velocity_deg_per_s = 45.0;
  options.effort_nm = 10.0;
  const urdf::ModelInterfaceSharedPtr model = parse(modelToUrdf(m, options));
  const auto j1 = model->getJoint("J1"), j2 = model->getJoint("J2");
  REQUIRE((j1 && j1->limits && j2 && j2->limits));
  CHECK(j1->limits->velocity == Approx(M_PI));  // the model's own
  CHECK(j1->limits->effort == 120.0);
  CHECK(j2->limits->velocity == Approx(M_PI / 4));  // the export's, for joints without
  CHECK(j2->limits->effort == 10.0);
  CHECK_THAT(modelToUrdf(m, options),
             Contains("Velocity given to the export, for the joints the model has none of: 45 "
                      "deg/s.\n  Effort given to the export, for the joints the model has none "
                      "of: 10 N m.\n"));
  // A model rated on every joint states nothing given.
  CHECK_THAT(modelToUrdf(rated(m), options), !Contains("given to the export"));
}
