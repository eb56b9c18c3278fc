// The robot module: one naming of configurations and singularity margins for every arm
// (armGeometry agrees with the PUMA's closed form), the numeric inverse kinematics on the PUMA
// and on a UR5, and makeArm's choice.
#include <catch2/catch.hpp>

#include "arms.hpp"

#include <robocal/formats/model_json.hpp>
#include <robocal/robot/numeric_ik.hpp>
#include <robocal/robot/puma_ik.hpp>

#include <cmath>
#include <cstdio>

using namespace robocal;
using namespace robocal::test;

namespace {

struct SweepResult {
  int poses = 0;
  int solved = 0;  // ok, within 1e-6 mm and 1e-6 deg, in the configuration asked for
  double worst_mm = 0;
  std::string first_failure;
};

// IK of `poses` random regular poses of `arm`, each asked in the configuration it was drawn in,
// without a seed.
SweepResult sweep(const Arm& arm, int poses, unsigned seed) {
  std::mt19937_64 rng(seed);
  SweepResult r;
  for (int i = 0; i < poses; ++i) {
    const JointsDeg q = randomRegularJoints(arm, rng);
    const ArmConfig config = arm.configOf(q);
    const Eigen::Isometry3d pose = arm.kinematics().toolPose(q);
    const IkSolution s = arm.solve(pose, config);
    ++r.poses;
    const bool good = s.ok() && s.position_error_mm < 1e-6 && s.angle_error_deg < 1e-6 &&
                      arm.configOf(s.joints_deg) == config;
    if (good) {
      ++r.solved;
      r.worst_mm = std::max(r.worst_mm, s.position_error_mm);
    } else if (r.first_failure.empty()) {
      r.first_failure = std::string(ikStatusName(s.status)) + " in " + armConfigName(config) +
                        ", error " + std::to_string(s.position_error_mm) + " mm";
    }
  }
  return r;
}

}  // namespace

TEST_CASE("armGeometry names configurations and margins as the PUMA's closed form does") {
  for (const unsigned seed : {0u, 1u, 2u}) {
    const Model model = seed == 0 ? puma560NominalModel() : calibratedLikePuma(seed);
    const PumaIk puma(model);
    std::mt19937_64 rng(seed + 10);
    for (int i = 0; i < 2000; ++i) {
      const JointsDeg q = randomRegularJoints(puma, rng);
      const ArmGeometry g = armGeometry(puma.kinematics(), q);
      INFO("seed " << seed << " joints " << q.transpose());
      CHECK(armConfigName(g.config()) == armConfigName(puma.configOf(q)));
      const SingularityMargins m = puma.singularityMargins(q);
      // The closed form reads the margins from the DH part of the model; a calibrated model's
      // link rotations move them a little.
      const double tol_deg = seed == 0 ? 1e-9 : 0.5, tol_mm = seed == 0 ? 1e-9 : 5.0;
      CHECK(g.margins.wrist_deg == Approx(m.wrist_deg).margin(tol_deg));
      CHECK(g.margins.elbow_deg == Approx(m.elbow_deg).margin(tol_deg));
      CHECK(g.margins.shoulder_mm == Approx(m.shoulder_mm).margin(tol_mm));
    }
  }
}

TEST_CASE("makeArm takes the PUMA's closed form for a PUMA, the numeric IK for another arm") {
  CHECK(std::string(makeArm(puma560NominalModel())->ikName()) == "PUMA closed form");
  CHECK(std::string(makeArm(calibratedLikePuma(3))->ikName()) == "PUMA closed form");
  CHECK(std::string(makeArm(ur5Model())->ikName()) == "numeric");
  Model zero_gain = ur5Model();
  zero_gain.joints[2].gain = 0;
  CHECK_THROWS_WITH(makeArm(zero_gain), Catch::Contains("joint 3 has a zero gain"));
}

TEST_CASE("numeric IK solves random regular poses in the configuration asked for") {
  // The acceptance's sweep is 10,000 poses an arm ([.ik-sweep] below, docs/robots.md).
  const NumericIk puma(puma560NominalModel()), calibrated(calibratedLikePuma(4)), ur5(ur5Model());
  for (const Arm* arm : {static_cast<const Arm*>(&puma), static_cast<const Arm*>(&calibrated),
                         static_cast<const Arm*>(&ur5)}) {
    const SweepResult r = sweep(*arm, 300, 7);
    INFO(arm->model().name << ": " << r.first_failure);
    CHECK(r.solved == r.poses);
    CHECK(r.worst_mm < 1e-6);
  }
}

TEST_CASE("numeric IK: every configuration of a pose, the seed's turn, unreachable and NaN") {
  const NumericIk ur5(ur5Model());
  std::mt19937_64 rng(11);
  const JointsDeg q = randomRegularJoints(ur5, rng);
  const Eigen::Isometry3d pose = ur5.kinematics().toolPose(q);
  // The configuration it was drawn in always has a solution; the others mostly do (a UR5
  // reaches most poses eight ways).
  int solved = 0;
  for (const IkSolution& s : ur5.solveAll(pose)) {
    if (!s.ok()) continue;
    ++solved;
    CHECK(ur5.configOf(s.joints_deg) == s.config);
    CHECK(s.position_error_mm < 1e-6);
  }
  CHECK(solved >= 2);
  CHECK(ur5.solve(pose, ur5.configOf(q)).ok());

  // A seed one step away: refine keeps to it and its 360-degree turns.
  JointsDeg seed = q;
  seed[0] += 2;
  const IkSolution near = ur5.refine(pose, ur5.configOf(q), seed);
  REQUIRE(near.ok());
  CHECK((near.joints_deg - q).cwiseAbs().maxCoeff() < 1e-6);

  Eigen::Isometry3d far = pose;
  far.translation() += Eigen::Vector3d(5000, 0, 0);
  const IkSolution out = ur5.solve(far, ur5.configOf(q));
  CHECK(out.status == IkStatus::kUnreachable);
  CHECK(out.joints_deg.allFinite());

  Eigen::Isometry3d nan_pose = pose;
  nan_pose.translation().x() = NAN;
  const IkSolution nan = ur5.solve(nan_pose, ur5.configOf(q));
  CHECK(nan.status == IkStatus::kUnreachable);
  CHECK(nan.joints_deg.allFinite());
}

TEST_CASE("numeric IK sweep: 10,000 regular poses an arm", "[.ik-sweep]") {
  const NumericIk numeric_puma(puma560NominalModel()), calibrated(calibratedLikePuma(5)),
      ur5(ur5Model()), rx160(loadModelFile(ROBOCAL_SOURCE_DIR "/config/rx160.json"));
  const PumaIk closed_form(calibratedLikePuma(5));
  for (const Arm* arm :
       {static_cast<const Arm*>(&numeric_puma), static_cast<const Arm*>(&calibrated),
        static_cast<const Arm*>(&closed_form), static_cast<const Arm*>(&ur5),
        static_cast<const Arm*>(&rx160)}) {
    const SweepResult r = sweep(*arm, 10000, 20261206);
    std::printf("%-28s %-17s solved %d of %d, worst %.1e mm%s%s\n", arm->model().name.c_str(),
                arm->ikName(), r.solved, r.poses, r.worst_mm, r.first_failure.empty() ? "" : "; ",
                r.first_failure.c_str());
    CHECK(r.solved == r.poses);
  }
}

TEST_CASE("the PUMA's closed form on a calibrated model solves poses at the edge of its reach") {
  // Within a few degrees of the straight or folded elbow a calibrated arm reaches a little
  // further or less far than its DH part: the closed form says "unreachable" for some of these
  // (45 of 10,000 regular poses before the seeded fallback), the model has an answer.
  const PumaIk ik(calibratedLikePuma(5));
  std::mt19937_64 rng(3);
  int poses = 0;
  while (poses < 200) {
    const JointsDeg q = randomRegularJoints(ik, rng);
    if (ik.singularityMargins(q).elbow_deg > 3) continue;
    ++poses;
    const IkSolution s = ik.solve(ik.kinematics().toolPose(q), ik.configOf(q));
    INFO("joints " << q.transpose() << ": " << ikStatusName(s.status));
    CHECK(s.ok());
    CHECK(s.position_error_mm < 1e-6);
  }
}

TEST_CASE("the whole range is drawn within the limits and away from the arm's own wrist") {
  // A UR5 whose joint 5 reads 0 where its angle is 90 deg: the wrist is singular at readings near
  // -90 and 90, not near 0, and the draws must say so from the arm's geometry, not the reading.
  Model model = ur5Model();
  model.joints[4].offset_deg = 90;
  const auto arm = makeArm(model);
  const std::vector<JointsDeg> joints = wholeRangeJoints(*arm, 500, 7);
  REQUIRE(joints.size() == 500);
  CHECK(joints == wholeRangeJoints(*arm, 500, 7));  // a seed draws the same vectors
  CHECK(joints != wholeRangeJoints(*arm, 500, 8));
  int near_zero_reading = 0;
  for (const JointsDeg& q : joints) {
    for (int j = 0; j < kJointCount; ++j) {
      CHECK(q[j] >= model.joints[j].min_deg);
      CHECK(q[j] <= model.joints[j].max_deg);
    }
    CHECK(arm->singularityMargins(q).wrist_deg >= 5);
    CHECK(std::abs(std::remainder(q[4] - 90, 180.0)) >= 5 - 1e-9);
    if (std::abs(std::remainder(q[4], 180.0)) < 5) ++near_zero_reading;
  }
  CHECK(near_zero_reading > 0);  // regular on this arm, so drawn
}
