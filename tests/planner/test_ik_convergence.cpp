// PumaIk::refine on calibrated-like models (the nominal PUMA 560 perturbed like a calibration
// finds it, up to three times as much): it converges on every reachable target away from the
// singularities, from the seeds robocal compensate gives it, and says kUnreachable, not
// kNoConvergence, for a target out of the calibrated arm's reach.
#include <catch2/catch.hpp>

#include <robocal/compensation/compensate.hpp>
#include <robocal/kinematics/units.hpp>
#include <robocal/robot/puma560.hpp>
#include <robocal/robot/puma_ik.hpp>
#include <robocal/sim/measurements.hpp>

#include <chrono>
#include <cmath>
#include <random>

using namespace robocal;

namespace {

Model perturbed(const Model& nominal, double factor, unsigned seed) {
  std::mt19937_64 rng(seed);
  return perturbModel(nominal, PerturbationSigmas{}.scaled(factor), rng);
}

// The margins robocal compensate calls near a singularity (CompensationOptions).
bool regular(const PumaIk& ik, const JointsDeg& q) {
  const SingularityMargins m = ik.singularityMargins(q);
  return m.wrist_deg > 2 && m.elbow_deg > 2 && m.shoulder_mm > 20;
}

// Readings `inset_deg` inside the limits and regular for each of the models; joint 5 within
// 2 deg of `joint5_deg` when given.
JointsDeg randomRegularJoints(const PumaIk& a, const PumaIk& b, double inset_deg,
                              std::mt19937_64& rng, const double* joint5_deg = nullptr) {
  for (;;) {
    JointsDeg q;
    for (int j = 0; j < kJointCount; ++j) {
      const JointParams& jp = a.model().joints[j];
      q[j] = std::uniform_real_distribution<double>(jp.min_deg + inset_deg,
                                                    jp.max_deg - inset_deg)(rng);
    }
    if (joint5_deg) q[4] = *joint5_deg + std::uniform_real_distribution<double>(-2, 2)(rng);
    if (regular(a, q) && regular(b, q)) return q;
  }
}

bool reached(const IkSolution& s) {
  return s.position_error_mm < 1e-4 && s.angle_error_deg < 1e-6 * kDegPerRad;
}

// Largest difference of two readings of the same joints, modulo each joint's turn.
double jointDistanceDeg(const Model& model, const JointsDeg& a, const JointsDeg& b) {
  double largest = 0;
  for (int j = 0; j < kJointCount; ++j)
    largest = std::max(
        largest, std::abs(std::remainder(a[j] - b[j], 360.0 / std::abs(model.joints[j].gain))));
  return largest;
}

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

TEST_CASE(
    "IK refine converges on every reachable target of a calibrated model away from the "
    "singularities",
    "[heavy]") {
  // As Compensator::forPose: the calibrated pose of regular readings, the nominal closed form
  // in the readings' configuration as the seed. Joint 5 near +-89 deg as well, where a user saw
  // "the inverse kinematics did not converge in this configuration".
  const Model nominal_model = puma560NominalModel();
  const PumaIk nominal(nominal_model);
  int targets = 0, seeds_missing = 0;
  double seconds = 0;
  for (const double factor : {1.0, 2.0, 3.0}) {
    for (unsigned seed = 1; seed <= 8; ++seed) {
      const PumaIk calibrated(perturbed(nominal_model, factor, seed));
      std::mt19937_64 rng(7000 * seed + static_cast<unsigned>(10 * factor));
      for (int trial = 0; trial < 1600; ++trial) {
        const double joint5 = trial % 2 ? 89.0 : -89.0;
        const JointsDeg q =
            randomRegularJoints(calibrated, calibrated, 0.5, rng, trial < 600 ? &joint5 : nullptr);
        const Eigen::Isometry3d target = calibrated.kinematics().toolPose(q);
        const ArmConfig config = calibrated.configOf(q);
        const IkSolution cf = nominal.solve(target, config);
        if (cf.status != IkStatus::kOk && cf.status != IkStatus::kOutsideLimits) {
          ++seeds_missing;  // the nominal arm does not reach it: compensate stops before refine
          continue;
        }
        const auto t0 = std::chrono::steady_clock::now();
        const IkSolution s = calibrated.refine(target, config, cf.joints_deg);
        seconds += secondsSince(t0);
        ++targets;
        INFO("factor " << factor << " seed " << seed << " trial " << trial << ": q "
                       << q.transpose() << ", seed " << cf.joints_deg.transpose() << ": "
                       << ikStatusName(s.status) << ", " << s.position_error_mm << " mm "
                       << s.angle_error_deg << " deg at " << s.joints_deg.transpose());
        REQUIRE(s.ok());
        REQUIRE(reached(s));
        REQUIRE(calibrated.configOf(s.joints_deg) == config);
        REQUIRE(jointDistanceDeg(calibrated.model(), s.joints_deg, q) < 1e-6);
      }
    }
  }
  WARN(targets << " targets converged (" << seeds_missing << " without a nominal solution), "
               << 1e6 * seconds / targets << " us per refine");
  CHECK(targets > 35000);
  CHECK(seconds / targets < 1e-3);  // about 5 us: far below, even on a loaded machine
}

TEST_CASE(
    "IK refine from the nominal readings: the calibrated solution, or unreachable when the "
    "nominal pose is out of the calibrated arm's reach",
    "[heavy]") {
  // As Compensator::forNominalJoints: the nominal pose of regular readings, refined with the
  // calibrated model from those readings. Near the straight elbow or the shoulder plane the
  // nominal pose may be out of the calibrated arm's reach: kUnreachable there, with the nearest
  // pose the configuration reaches (the arm straight or the wrist centre on the shoulder plane).
  const Model nominal_model = puma560NominalModel();
  const PumaIk nominal(nominal_model);
  int converged = 0, unreachable = 0, outside_limits = 0;
  for (const double factor : {1.0, 2.0, 3.0}) {
    for (unsigned seed = 1; seed <= 5; ++seed) {
      const PumaIk calibrated(perturbed(nominal_model, factor, seed));
      std::mt19937_64 rng(1000 * seed + static_cast<unsigned>(factor));
      for (int trial = 0; trial < 300; ++trial) {
        const JointsDeg q = randomRegularJoints(nominal, calibrated, 3, rng);
        const Eigen::Isometry3d target = nominal.kinematics().toolPose(q);
        const ArmConfig config = nominal.configOf(q);
        const IkSolution s = calibrated.refine(target, config, q);
        INFO("factor " << factor << " seed " << seed << " trial " << trial << ": q "
                       << q.transpose() << ": " << ikStatusName(s.status) << ", "
                       << s.position_error_mm << " mm " << s.angle_error_deg << " deg at "
                       << s.joints_deg.transpose());
        REQUIRE(s.status != IkStatus::kNoConvergence);
        REQUIRE(s.status != IkStatus::kSingular);
        REQUIRE(s.joints_deg.allFinite());
        if (s.status == IkStatus::kUnreachable) {
          ++unreachable;
          const SingularityMargins m = calibrated.singularityMargins(s.joints_deg);
          CHECK((m.elbow_deg < 1 || m.shoulder_mm < 5));
          CHECK(calibrated.configOf(s.joints_deg) == config);
          CHECK(s.position_error_mm > 1e-4);
          continue;
        }
        // A calibration can move a joint's solution a few degrees, past a limit 3 deg away.
        if (s.status == IkStatus::kOutsideLimits)
          ++outside_limits;
        else
          ++converged;
        CHECK(reached(s));
        CHECK(calibrated.configOf(s.joints_deg) == config);
      }
    }
  }
  WARN(converged << " converged, " << unreachable << " out of the calibrated arm's reach, "
                 << outside_limits << " outside the limits");
  CHECK(converged > 4000);
  CHECK(unreachable < 0.05 * converged);
}

TEST_CASE(
    "compensating 200 reachable targets of a 3x calibration: every one converges, in well "
    "under a second") {
  const Model nominal_model = puma560NominalModel();
  const PumaIk nominal(nominal_model);
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const Model calibrated_model = perturbed(nominal_model, 3.0, seed);
    const PumaIk calibrated(calibrated_model);
    const Compensator compensator(nominal_model, calibrated_model);
    std::mt19937_64 rng(seed);
    std::vector<Eigen::Isometry3d> poses;
    std::vector<ArmConfig> configs;
    while (poses.size() < 200) {
      const JointsDeg q = randomRegularJoints(calibrated, calibrated, 0.5, rng);
      const Eigen::Isometry3d pose = calibrated.kinematics().toolPose(q);
      if (!nominal.solve(pose, calibrated.configOf(q)).ok()) continue;
      poses.push_back(pose);
      configs.push_back(calibrated.configOf(q));
    }
    const auto t0 = std::chrono::steady_clock::now();
    for (size_t i = 0; i < poses.size(); ++i) {
      const CompensatedTarget t = compensator.forPose(poses[i], configs[i]);
      INFO("seed " << seed << " target " << i << ": " << compensationStatusName(t.status) << " "
                   << t.reason);
      CHECK(t.status != CompensationStatus::kUnreachable);
      CHECK(t.position_residual_mm < 1e-4);
      CHECK(t.angle_residual_deg < 1e-6 * kDegPerRad);
    }
    CHECK(secondsSince(t0) < 1.0);
  }
}
