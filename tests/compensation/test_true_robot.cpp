// The simulated true robot that is not its model (sim/true_robot.hpp) and its truth file: each
// effect has its documented size and sign, the ideal robot is exactly its model, and the truth
// file round-trips and refuses bad keys by path.
#include <catch2/catch.hpp>

#include <robocal/formats/error.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/kinematics/kinematics.hpp>
#include <robocal/robot/puma560.hpp>
#include <robocal/sim/measurements.hpp>
#include <robocal/sim/true_robot_json.hpp>

#include <nlohmann/json.hpp>

#include <unistd.h>
#include <cstdio>
#include <fstream>

using namespace robocal;
using Catch::Matchers::Contains;

namespace {

JointsDeg joints(double a, double b, double c, double d, double e, double f) {
  JointsDeg q;
  q << a, b, c, d, e, f;
  return q;
}

}  // namespace

TEST_CASE("true robot: the ideal one is exactly its model, and each effect has its size and sign") {
  const Model model = puma560NominalModel();
  const TrueRobot ideal{model, Realism::ideal()};
  const TrueRobot typical{model, Realism::typical(puma560NominalModel().compliance->load)};
  const JointsDeg q = joints(10, 30, -160, 20, 40, 30);
  CHECK(ideal.effectiveReadings(q, kPositiveApproach) == q);
  CHECK(ideal.measuredLength(150.3, 150) == 150.3);

  SECTION("backlash: half its width, in the direction of the last motion") {
    TrueRobot backlash{model, Realism::ideal()};
    backlash.realism.backlash_deg = {0.02, 0.02, 0.02, 0.02, 0.02, 0.02};
    const JointsDeg plus = backlash.effectiveReadings(q, kPositiveApproach);
    const JointsDeg minus = backlash.effectiveReadings(q, {-1, -1, -1, -1, -1, -1});
    for (int j = 0; j < kJointCount; ++j) {
      CHECK(plus[j] - q[j] == Approx(0.01 / model.joints[j].gain));
      CHECK(plus[j] - minus[j] == Approx(0.02 / model.joints[j].gain));
    }
    const Approach a = approachOf(q, joints(11, 30, -161, 20, 40, 29), kPositiveApproach);
    CHECK(a == Approach{1, 1, -1, 1, 1, -1});  // joints that did not move keep their direction
  }
  SECTION("gravity: no torque on the vertical joint 1, the upper arm's weight on joint 2") {
    const auto level =
        typical.gravityTorqueNm(joints(0, 0, -180, 0, 0, 0), 1.0, Eigen::Vector3d(0, 0, 60));
    const auto upright =
        typical.gravityTorqueNm(joints(0, 90, -180, 0, 0, 0), 1.0, Eigen::Vector3d(0, 0, 60));
    CHECK(std::abs(level[0]) < 1e-9);
    CHECK(std::abs(level[1]) > 2 * std::abs(upright[1]));
    // A heavier payload weighs more on joint 2, with the sign of the arm's own weight.
    const auto loaded =
        typical.gravityTorqueNm(joints(0, 0, -180, 0, 0, 0), 10.0, Eigen::Vector3d(0, 0, 60));
    CHECK(std::abs(loaded[1]) > std::abs(level[1]));
    CHECK(loaded[1] * level[1] > 0);
  }
  SECTION("the typical compliance twists joints 2 and 3 by a few hundredths of a degree") {
    double worst = 0;
    for (double j2 = -40; j2 <= 220; j2 += 10)
      for (double j3 = -220; j3 <= 40; j3 += 10) {
        const auto t = typical.gravityTorqueNm(joints(0, j2, j3, 0, 30, 0), 1.0,
                                               typical.realism.compliance.load.payload_com_mm);
        worst = std::max(worst, std::abs(typical.realism.compliance.deg_per_nm[1] * t[1]));
      }
    CHECK(worst > 0.02);
    CHECK(worst < 0.06);
  }
  SECTION("warm-up: links grow toward alpha * warm-up, the base does not") {
    const Model cold = typical.modelAt(0), warm = typical.modelAt(1e6);
    CHECK(cold.links[2].x_mm == model.links[2].x_mm);
    CHECK(warm.links[2].x_mm == Approx(model.links[2].x_mm * (1 + 11.7e-6 * 3)).epsilon(1e-12));
    CHECK(warm.links[0].z_mm == model.links[0].z_mm);
    const double half = typical.modelAt(30 * std::log(2.0)).links[2].x_mm - model.links[2].x_mm;
    CHECK(half == Approx(0.5 * (warm.links[2].x_mm - model.links[2].x_mm)));
  }
  SECTION("the instrument: gain, nonlinearity and the bar's length standard") {
    TrueRobot bar{model, Realism::ideal()};
    bar.realism.lvdt_gain_error = 1e-3;
    CHECK(bar.measuredLength(151, 150) == Approx(151.001));
    bar.realism.lvdt_gain_error = 0;
    bar.realism.lvdt_nonlinearity_mm = 0.0075;
    CHECK(bar.measuredLength(151, 150) == Approx(151.0075));  // at half the travel: the peak
    CHECK(bar.measuredLength(150, 150) == Approx(150));
    bar.realism.lvdt_nonlinearity_mm = 0;
    bar.realism.bar_length_error = 1e-4;  // the bar is 15 um longer than stated
    CHECK(bar.measuredLength(150, 150) == Approx(150 - 0.015));
  }
}

TEST_CASE("true robot: an ideal run measures what the model says, a typical one does not") {
  const Model model = puma560NominalModel();
  ShellRequest req;
  req.connection = {0, 0};
  req.points = 30;
  std::mt19937_64 rng(5);
  const ShellPoses poses = shellPoses(model, req, rng);
  REQUIRE(poses.poses.size() > 20);
  std::mt19937_64 a(6), b(6);
  const auto exact = measureShell(model, req, poses.poses, {0, 0}, a);
  RunTrack track;
  const auto typical =
      measureShell(TrueRobot{model, Realism::typical(puma560NominalModel().compliance->load)}, req,
                   poses.poses, {0, 0}, b, track);
  REQUIRE(exact.size() == typical.size());
  double worst = 0;
  for (size_t i = 0; i < exact.size(); ++i) {
    CHECK(exact[i].length_mm == Approx(req.radius_mm).margin(5));
    worst = std::max(worst, std::abs(exact[i].length_mm - typical[i].length_mm));
  }
  CHECK(worst > 0.005);  // tens of micrometres: backlash, compliance, the LVDT
  CHECK(worst < 0.5);
  CHECK(track.minutes == Approx(0.1 * exact.size()));
}

TEST_CASE("truth file: realism round-trips, model readers ignore it, bad keys are named") {
  char path[] = "/tmp/robocal-truth-XXXXXX";
  const int fd = ::mkstemp(path);
  REQUIRE(fd >= 0);
  ::close(fd);
  TrueRobot t{puma560NominalModel(), Realism::typical(puma560NominalModel().compliance->load)};
  t.realism.bar_length_error = 2e-5;
  saveTruthFile(path, t);
  const TrueRobot back = loadTruthFile(path);
  CHECK(back.realism.backlash_deg == t.realism.backlash_deg);
  CHECK(back.realism.compliance.load.link_com_mm[1] == t.realism.compliance.load.link_com_mm[1]);
  CHECK(back.realism.bar_length_error == t.realism.bar_length_error);
  CHECK(back.realism.warmup_k == t.realism.warmup_k);
  CHECK(toParams(loadModelFile(path)) == toParams(t.model));  // a model reader sees the geometry

  nlohmann::json j = nlohmann::json::parse(readTextFile(path));
  j["realism"]["backlash_degs"] = j["realism"]["backlash_deg"];
  std::ofstream(path) << j.dump();
  CHECK_THROWS_WITH(loadTruthFile(path), Contains("realism.backlash_degs: unknown key"));
  j["realism"].erase("backlash_degs");
  j["realism"]["backlash_deg"][2] = -0.01;
  std::ofstream(path) << j.dump();
  CHECK_THROWS_WITH(loadTruthFile(path), Contains("realism.backlash_deg[2]"));
  std::remove(path);
}

TEST_CASE("a model with compliance twists its joints as the true robot's compliance does") {
  Model rigid = puma560NominalModel();
  rigid.joints[1].gain = 1.002;  // the twist is an angle: divided by the gain in the readings
  rigid.joints[2].gain = 0.997;
  TrueRobot truth{rigid, Realism::ideal()};
  truth.realism.compliance = Realism::typical(puma560NominalModel().compliance->load).compliance;
  Model compliant = rigid;
  compliant.compliance = truth.realism.compliance;
  const Kinematics rigid_kin(rigid), compliant_kin(compliant);
  double largest_mm = 0;
  for (const JointsDeg& q : {joints(10, 30, -160, 20, 40, 30), joints(-40, 100, -20, 0, 60, 0),
                             joints(90, -30, -200, -50, -70, 100)}) {
    const Eigen::Vector3d twisted = compliant_kin.toolPose(q).translation();
    const Eigen::Vector3d expected =
        rigid_kin.toolPose(truth.effectiveReadings(q, kPositiveApproach)).translation();
    CHECK((twisted - expected).norm() < 1e-9);
    CHECK((compliant_kin.ballPosition(q, rigid.balls_mm[0]) -
           rigid_kin.ballPosition(compliant_kin.twistedReadings(q), rigid.balls_mm[0]))
              .norm() < 1e-9);
    largest_mm = std::max(largest_mm, (twisted - rigid_kin.toolPose(q).translation()).norm());
  }
  CHECK(largest_mm > 0.1);  // a few hundredths of a degree at the arm's reach

  SECTION("the model file carries it; a file without it is a rigid arm; bad keys are named") {
    const Model back = parseModel(formatModel(compliant), "m.json");
    REQUIRE(back.compliance);
    CHECK(back.compliance->deg_per_nm == compliant.compliance->deg_per_nm);
    CHECK(back.compliance->load.payload_kg == compliant.compliance->load.payload_kg);
    CHECK(back.compliance->load.link_com_mm[2] == compliant.compliance->load.link_com_mm[2]);
    Model older = rigid;  // a file from before the key
    older.compliance.reset();
    CHECK(formatModel(older).find("compliance") == std::string::npos);
    CHECK_FALSE(parseModel(formatModel(older), "m.json").compliance);
    nlohmann::json j = nlohmann::json::parse(formatModel(compliant));
    j["compliance"]["payload_kgs"] = 1;
    CHECK_THROWS_WITH(parseModel(j.dump(), "m.json"),
                      Contains("m.json: compliance.payload_kgs: unknown key"));
    j = nlohmann::json::parse(formatModel(compliant));
    j["compliance"]["compliance_deg_per_nm"][1] = 3;
    CHECK_THROWS_WITH(parseModel(j.dump(), "m.json"),
                      Contains("compliance.compliance_deg_per_nm[1]"));
  }
}
