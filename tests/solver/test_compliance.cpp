// Gravity compliance identified with the 54 parameters (solver/compliance_fit.hpp): found on a
// true robot whose joints twist under gravity, not invented on one that is rigid, and the arm's
// whole range judged better for it.
#include <catch2/catch.hpp>

#include "fit_fixtures.hpp"

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/robot/puma560.hpp>
#include <robocal/solver/assessment.hpp>

#include <cmath>
#include <random>

using namespace robocal;
using namespace robocal::test;

namespace {

// Samples of `truth` with `realism` on the shells of all nine connections at two radii.
std::vector<Sample> measured(const TrueRobot& truth, double noise_mm, unsigned seed) {
  std::vector<Sample> samples;
  std::mt19937_64 rng(seed);
  RunTrack track;
  for (const double extension_mm : {0.0, 150.0}) {
    const Shells shells = planShells(puma560NominalModel(), "all", extension_mm, 40, seed + 1);
    for (size_t i = 0; i < shells.requests.size(); ++i) {
      const auto s =
          measureShell(truth, shells.requests[i], shells.poses[i], {noise_mm, 0}, rng, track);
      samples.insert(samples.end(), s.begin(), s.end());
    }
  }
  return samples;
}

// RMS ball-1 position error of `model` against the true robot over joint vectors drawn within
// the arm's limits (its whole range).
double wholeRangeErrorMm(const Model& model, const TrueRobot& truth) {
  std::mt19937_64 rng(7);
  const Kinematics kin(model), true_kin(truth.model);
  double sum = 0;
  const int n = 300;
  for (int i = 0; i < n; ++i) {
    JointsDeg q;
    for (int j = 0; j < kJointCount; ++j)
      q[j] = std::uniform_real_distribution<double>(model.joints[j].min_deg,
                                                    model.joints[j].max_deg)(rng);
    const Eigen::Vector3d ball = model.balls_mm[0];
    sum += (kin.ballPosition(q, ball) -
            true_kin.ballPosition(truth.effectiveReadings(q, kPositiveApproach), ball))
               .squaredNorm();
  }
  return std::sqrt(sum / n);
}

}  // namespace

TEST_CASE("compliance: the twist of the loaded joints is identified, and only where it is") {
  const Model nominal = puma560NominalModel();
  const Model geometry = perturbed(1.0, 31);
  Realism twisting = Realism::ideal();
  twisting.compliance = Realism::typical(puma560NominalModel().compliance->load).compliance;
  const double noise_mm = 0.02;
  AssessOptions with;
  with.identify_compliance = true;

  SECTION("a true robot that twists: joints 2 and 3 found, the whole range better for it") {
    const TrueRobot truth{geometry, twisting};
    const std::vector<Sample> samples = measured(truth, noise_mm, 40);
    const FitAssessment rigid = assessFit(nominal, samples);
    const FitAssessment compliant = assessFit(nominal, samples, with);
    REQUIRE(compliant.compliance);
    const ComplianceEstimate& c = *compliant.compliance;
    INFO(c.summary());
    CHECK(c.joints == std::vector<int>{1, 2});
    CHECK(c.identified);
    for (int j : c.joints) {
      const double true_value = twisting.compliance.deg_per_nm[j];
      CHECK(std::abs(c.compliance.deg_per_nm[j] - true_value) < 4 * c.sigma_deg_per_nm[j]);
    }
    CHECK(c.sigma_deg_per_nm[1] < 0.5 * twisting.compliance.deg_per_nm[1]);
    REQUIRE(compliant.calibrated.compliance);
    CHECK(compliant.calibrated.compliance->deg_per_nm == c.compliance.deg_per_nm);
    // The geometry no longer absorbs the twist: the fit's residual is the noise.
    CHECK(compliant.fit.sigma_mm < rigid.fit.sigma_mm);
    CHECK(compliant.fit.sigma_mm < 1.2 * noise_mm);
    const double rigid_mm = wholeRangeErrorMm(rigid.calibrated, truth);
    const double compliant_mm = wholeRangeErrorMm(compliant.calibrated, truth);
    INFO("whole range: rigid fit " << rigid_mm << " mm, with compliance " << compliant_mm << " mm");
    CHECK(compliant_mm < 0.7 * rigid_mm);
  }
  SECTION("a rigid true robot: no twist beyond its uncertainty, and the model stays rigid") {
    const TrueRobot truth{geometry, Realism::ideal()};
    const FitAssessment compliant = assessFit(nominal, measured(truth, noise_mm, 41), with);
    REQUIRE(compliant.compliance);
    const ComplianceEstimate& c = *compliant.compliance;
    INFO(c.summary());
    CHECK(c.joints == std::vector<int>{1, 2});
    for (int j : c.joints) CHECK(std::abs(c.fitted_deg_per_nm[j]) < 4 * c.sigma_deg_per_nm[j]);
    // Not told from noise: the model stays rigid, and says so.
    CHECK_FALSE(c.identified);
    CHECK(c.compliance.deg_per_nm == std::array<double, kJointCount>{});
    CHECK_FALSE(compliant.calibrated.compliance->twists());
    CHECK_THAT(c.summary(), Catch::Contains("the model stays rigid"));
  }
}
