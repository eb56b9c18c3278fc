#include <catch2/catch.hpp>

#include "arms.hpp"

#include <robocal/kinematics/units.hpp>
#include <robocal/robot/puma560.hpp>
#include <robocal/robot/puma_ik.hpp>

#include <cmath>
#include <random>

using namespace robocal;
using robocal::test::randomRegularJoints;

namespace {

JointsDeg deg(double a, double b, double c, double d, double e, double f) {
  JointsDeg q;
  q << a, b, c, d, e, f;
  return q;
}

double angleBetweenDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return std::abs(Eigen::AngleAxisd(a * b.transpose()).angle()) * kDegPerRad;
}

}  // namespace

TEST_CASE("arm configuration names round-trip") {
  for (int i = 0; i < kArmConfigCount; ++i) {
    const ArmConfig c = armConfigFromIndex(i);
    CHECK(armConfigIndex(c) == i);
    const auto parsed = parseArmConfig(armConfigName(c));
    REQUIRE(parsed);
    CHECK(*parsed == c);
  }
  CHECK_FALSE(parseArmConfig("right-up"));
}

TEST_CASE("closed-form IK: FK(IK(pose)) == pose in all eight configurations") {
  const PumaIk ik(puma560NominalModel());
  std::mt19937_64 rng(42);
  std::array<int, kArmConfigCount> seen{};
  for (int trial = 0; trial < 400; ++trial) {
    const JointsDeg q = randomRegularJoints(ik, rng);
    seen[armConfigIndex(ik.configOf(q))]++;
    const Eigen::Isometry3d pose = ik.kinematics().toolPose(q);
    for (int c = 0; c < kArmConfigCount; ++c) {
      const ArmConfig config = armConfigFromIndex(c);
      const IkSolution s = ik.closedForm(pose, config);
      INFO("trial " << trial << " config " << armConfigName(config) << " status "
                    << ikStatusName(s.status));
      REQUIRE(s.joints_deg.allFinite());
      if (s.status == IkStatus::kUnreachable) continue;  // this configuration may not reach
      const Eigen::Isometry3d back = ik.kinematics().toolPose(s.joints_deg);
      CHECK((back.translation() - pose.translation()).norm() < 1e-6);
      CHECK(angleBetweenDeg(back.linear(), pose.linear()) < 1e-7);
      if (s.status == IkStatus::kOk || s.status == IkStatus::kOutsideLimits)
        CHECK(ik.configOf(s.joints_deg) == config);
    }
    // The configuration the pose was made in gives the same joints back.
    const IkSolution own = ik.solve(pose, ik.configOf(q), &q);
    REQUIRE(own.ok());
    CHECK((own.joints_deg - q).cwiseAbs().maxCoeff() < 1e-6);
  }
  for (int c = 0; c < kArmConfigCount; ++c) {
    INFO("configuration " << armConfigName(armConfigFromIndex(c)));
    CHECK(seen[c] > 0);  // the random poses covered every configuration
  }
}

TEST_CASE("IK refines the closed form for a perturbed (calibrated) model") {
  Model model = puma560NominalModel();
  model.links[2].x_mm += 0.7;
  model.links[3].z_mm -= 0.4;
  model.links[2].ry_deg += 0.05;
  model.links[4].rz_deg -= 0.03;
  model.links[0].y_mm += 1.5;
  model.joints[1].offset_deg += 0.2;
  model.joints[2].gain = 1.001;
  const PumaIk ik(model);
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 100; ++trial) {
    const JointsDeg q = randomRegularJoints(ik, rng);
    const Eigen::Isometry3d pose = ik.kinematics().toolPose(q);
    const ArmConfig config = ik.configOf(q);
    const IkSolution cf = ik.closedForm(pose, config, &q);
    const IkSolution s = ik.solve(pose, config, &q);
    INFO("trial " << trial << " " << ikStatusName(s.status));
    CHECK(cf.position_error_mm > 1e-3);  // the closed form alone is not exact here
    REQUIRE(s.ok());
    CHECK(s.position_error_mm < 1e-6);
    CHECK(s.angle_error_deg < 1e-6);
    CHECK(ik.configOf(s.joints_deg) == config);
  }
}

TEST_CASE("IK answers unreachable and singular poses with a status, never NaN") {
  const PumaIk ik(puma560NominalModel());
  const Kinematics& kin = ik.kinematics();
  SECTION("far out of reach") {
    Eigen::Isometry3d far = kin.toolPose(deg(0, 90, -90, 0, 45, 0));
    far.translation() += Eigen::Vector3d(3000, 0, 0);
    for (const IkSolution& s : ik.solveAll(far)) {
      CHECK(s.status == IkStatus::kUnreachable);
      CHECK(s.joints_deg.allFinite());
    }
  }
  SECTION("a non-finite target") {
    Eigen::Isometry3d bad = Eigen::Isometry3d::Identity();
    bad.translation().x() = NAN;
    const IkSolution s = ik.solve(bad, ArmConfig{});
    CHECK(s.status == IkStatus::kUnreachable);
    CHECK(s.joints_deg.allFinite());
  }
  SECTION("wrist singular: joint 5 at zero") {
    const JointsDeg q = deg(10, 30, -120, 20, 0, 15);
    const Eigen::Isometry3d pose = kin.toolPose(q);
    for (bool flip : {false, true}) {
      ArmConfig c = ik.configOf(q);
      c.wrist_flip = flip;
      const IkSolution s = ik.solve(pose, c, &q);
      CHECK(s.status == IkStatus::kSingular);
      CHECK(s.joints_deg.allFinite());
      // Still a pose-exact answer: joints 4 and 6 share the rotation.
      CHECK((kin.toolPose(s.joints_deg).translation() - pose.translation()).norm() < 1e-6);
    }
  }
  SECTION("elbow singular: arm stretched") {
    const double straight = -std::atan2(433.07, 20.32) * kDegPerRad;
    const JointsDeg q = deg(0, 40, straight, 0, 30, 0);
    CHECK(ik.singularityMargins(q).elbow_deg < 1e-6);
    const IkSolution s = ik.solve(kin.toolPose(q), ik.configOf(q));
    CHECK(s.status == IkStatus::kSingular);
    CHECK(s.joints_deg.allFinite());
  }
  SECTION("inside the shoulder offset: wrist centre too close to joint 1's axis") {
    // Put the flange just over joint 1's axis, pointing up: the wrist centre is on the axis,
    // closer to it than d3 = 149.09 mm.
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() =
        kin.chainFrames(JointsDeg::Zero())[0].translation() + Eigen::Vector3d(0, 0, 600 + 56.25);
    for (const IkSolution& s : ik.solveAll(pose)) {
      CHECK(s.status == IkStatus::kUnreachable);
      CHECK(s.joints_deg.allFinite());
    }
  }
}

TEST_CASE("IK keeps readings inside the joint limits and reports poses outside them") {
  const PumaIk ik(puma560NominalModel());
  // Joint 6 at 250 deg is inside its +/-266 limits; its 360-degree twin -110 is too: the answer
  // follows `near`.
  const JointsDeg q = deg(5, 20, -150, 30, 40, 250);
  const Eigen::Isometry3d pose = ik.kinematics().toolPose(q);
  const IkSolution a = ik.solve(pose, ik.configOf(q), &q);
  REQUIRE(a.ok());
  CHECK(a.joints_deg[5] == Approx(250).margin(1e-6));
  JointsDeg other = q;
  other[5] = -100;
  const IkSolution b = ik.solve(pose, ik.configOf(q), &other);
  REQUIRE(b.ok());
  CHECK(b.joints_deg[5] == Approx(-110).margin(1e-6));

  // Joint 4 at -150 (= 210) fits neither turn of its -110..170 range.
  const JointsDeg outside = deg(5, 20, -150, -150, 40, 0);
  const IkSolution c = ik.solve(ik.kinematics().toolPose(outside), ik.configOf(outside));
  CHECK(c.status == IkStatus::kOutsideLimits);
  CHECK(c.joints_deg.allFinite());
}
