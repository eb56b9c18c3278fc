// Gravity compliance identified with the 54 parameters (solver/compliance_fit.hpp): found on a
// true robot whose joints twist under gravity, not invented on one that is rigid, and the arm's
// whole range judged better for it.
#include <catch2/catch.hpp>

#include <algorithm>

#include "fit_fixtures.hpp"

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/twist.hpp>
#include <robocal/robot/puma560.hpp>
#include <robocal/solver/assessment.hpp>
#include <robocal/solver/problem.hpp>

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
  AssessOptions rigid_fit;  // the 54 alone (robocal solve --rigid)
  rigid_fit.identify_compliance = false;

  SECTION("a true robot that twists: joints 2 and 3 found, the whole range better for it") {
    const TrueRobot truth{geometry, twisting};
    const std::vector<Sample> samples = measured(truth, noise_mm, 40);
    const FitAssessment rigid = assessFit(nominal, samples, rigid_fit);
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
    // Not kept, but known only to its uncertainty: the covariance carries it, and the predicted
    // errors grow by it.
    REQUIRE(c.covariance.rows() == twistCovarianceIndex(kJointCount));
    for (int j : c.joints) {
      const int t = twistCovarianceIndex(j);
      CHECK(std::sqrt(c.covariance(t, t)) == Approx(c.sigma_deg_per_nm[j]));
    }
    CHECK(calibratedCovariance(compliant).rows() == twistCovarianceIndex(kJointCount));
    const FitAssessment rigid = assessFit(nominal, compliant.samples, rigid_fit);
    CHECK(compliant.fit.params == rigid.fit.params);
    // Taken as known, the twist gives back the rigid fit's covariance (the health check's).
    const Eigen::MatrixXd known = covarianceAtKnownTwist(c.covariance);
    CHECK((known - rigid.fit.covariance).norm() < 1e-6 * rigid.fit.covariance.norm());
    CHECK((c.covariance.topLeftCorner(kParamCount, kParamCount) - rigid.fit.covariance).norm() >
          1e-3 * rigid.fit.covariance.norm());
    CHECK(compliant.predicted_ball_error_rms_mm > rigid.predicted_ball_error_rms_mm);
    // Most where the shells are not: over the arm's whole range.
    std::vector<Sample> whole;
    std::mt19937_64 rng(3);
    for (int i = 0; i < 200; ++i) {
      JointsDeg q;
      for (int j = 0; j < kJointCount; ++j)
        q[j] = std::uniform_real_distribution<double>(nominal.joints[j].min_deg,
                                                      nominal.joints[j].max_deg)(rng);
      whole.push_back(makeSample(1, {0, 0}, 0, 0, 0, q, 0));
    }
    const auto rms = [](const std::vector<double>& e) {
      double sum = 0;
      for (double x : e) sum += x * x;
      return std::sqrt(sum / e.size());
    };
    const double with_twist_mm =
        rms(predictedBallErrors(compliant.calibrated, calibratedCovariance(compliant), whole));
    const double rigid_mm =
        rms(predictedBallErrors(rigid.calibrated, calibratedCovariance(rigid), whole));
    INFO("whole range predicted: " << rigid_mm << " mm rigid, " << with_twist_mm
                                   << " mm with the twist's uncertainty");
    CHECK(with_twist_mm > 1.4 * rigid_mm);
  }
}

TEST_CASE("compliance: the identified twist's covariance joins the 54's as the batch fit's") {
  Realism twisting = Realism::ideal();
  twisting.compliance = Realism::typical(puma560NominalModel().compliance->load).compliance;
  const TrueRobot truth{perturbed(1.0, 31), twisting};
  const std::vector<Sample> samples = measured(truth, 0.02, 40);
  AssessOptions with;
  with.identify_compliance = true;
  const FitAssessment fit = assessFit(puma560NominalModel(), samples, with);
  REQUIRE(fit.compliance);
  REQUIRE(fit.compliance->identified);
  const Eigen::MatrixXd& joint = fit.compliance->covariance;
  REQUIRE(joint.rows() == kParamCount + kJointCount);
  // The batch fit of the free parameters and the twists together, linearised at the solution:
  // sigma^2 ([J_p J_c]^T [J_p J_c])^-1, the twist's columns by differences of the residuals.
  const Model& at = fit.calibrated;
  Eigen::VectorXd r0;
  Eigen::MatrixXd full;
  evaluateProblem(at, toParams(at), samples, r0, &full);
  const std::vector<int>& free = fit.fit.free_params;
  const std::vector<int>& twisted = fit.compliance->joints;
  const Eigen::Index p = static_cast<Eigen::Index>(free.size());
  const Eigen::Index k = static_cast<Eigen::Index>(twisted.size());
  Eigen::MatrixXd jac(full.rows(), p + k);
  for (Eigen::Index a = 0; a < p; ++a) jac.col(a) = full.col(free[a]);
  for (Eigen::Index c = 0; c < k; ++c) {
    constexpr double kStep = 1e-5;  // deg/(N m)
    Model plus = at, minus = at;
    plus.compliance->deg_per_nm[twisted[c]] += kStep;
    minus.compliance->deg_per_nm[twisted[c]] -= kStep;
    Eigen::VectorXd rp, rm;
    evaluateProblem(plus, toParams(plus), samples, rp, nullptr);
    evaluateProblem(minus, toParams(minus), samples, rm, nullptr);
    jac.col(p + c) = (rp - rm) / (2 * kStep);
  }
  const double s2 = fit.fit.sigma_mm * fit.fit.sigma_mm;
  const Eigen::MatrixXd batch =
      s2 * (jac.transpose() * jac).ldlt().solve(Eigen::MatrixXd::Identity(p + k, p + k));
  std::vector<int> order = free;  // the batch's rows in the joint covariance's layout
  for (int j : twisted) order.push_back(kParamCount + j);
  double worst = 0;
  for (Eigen::Index a = 0; a < p + k; ++a)
    for (Eigen::Index b = 0; b < p + k; ++b) {
      // Each entry against its scale, sqrt(var_a var_b): a correlation's error.
      const double scale = std::sqrt(batch(a, a) * batch(b, b));
      worst = std::max(worst, std::abs(joint(order[a], order[b]) - batch(a, b)) / scale);
    }
  INFO("largest difference " << worst << " of the entries' scale; twist sigmas "
                             << std::sqrt(joint(kParamCount + 1, kParamCount + 1)) << ", "
                             << std::sqrt(batch(p, p)));
  CHECK(worst < 0.01);
  // The joints not fitted (the wrist's torque is small at these poses) are counted at the size of
  // the most compliant fitted one, independent of the rest: the batch has no such rows.
  Eigen::MatrixXd fitted_only = joint;
  for (int j = 0; j < kJointCount; ++j) {
    const int t = kParamCount + j;
    if (std::find(twisted.begin(), twisted.end(), j) != twisted.end()) continue;
    CHECK(std::sqrt(joint(t, t)) ==
          Approx(std::max({std::abs(at.compliance->deg_per_nm[1]),
                           std::abs(at.compliance->deg_per_nm[2]),
                           std::sqrt(joint(kParamCount + 1, kParamCount + 1)),
                           std::sqrt(joint(kParamCount + 2, kParamCount + 2))})));
    CHECK(joint.row(t).cwiseAbs().sum() == Approx(joint(t, t)));
    fitted_only(t, t) = 0;
  }
  // What the calibration measured alone: the health check's whitening (solver/health.cpp).
  CHECK((withoutUnfittedTwists(joint) - fitted_only).cwiseAbs().maxCoeff() == 0);
  // The predicted ball errors carry it: the batch covariance carried to the ball by the position
  // Jacobian, the twist's columns again by differences of the model.
  const std::vector<double> predicted = predictedBallErrors(at, fitted_only, samples);
  const Kinematics kin(at);
  for (size_t i = 0; i < samples.size(); i += 97) {
    const Sample& s = samples[i];
    const Eigen::Vector3d& ball = at.balls_mm[s.ball_index];
    PositionJacobian g;
    kin.ballPositionJacobian(s.joints_deg, ball, g);
    Eigen::MatrixXd gb(3, p + k);
    for (Eigen::Index a = 0; a < p; ++a) gb.col(a) = g.col(free[a]);
    for (Eigen::Index c = 0; c < k; ++c) {
      Model plus = at, minus = at;
      plus.compliance->deg_per_nm[twisted[c]] += 1e-5;
      minus.compliance->deg_per_nm[twisted[c]] -= 1e-5;
      gb.col(p + c) = (Kinematics(plus).ballPosition(s.joints_deg, ball) -
                       Kinematics(minus).ballPosition(s.joints_deg, ball)) /
                      2e-5;
    }
    CHECK(predicted[i] == Approx(std::sqrt((gb * batch * gb.transpose()).trace())).epsilon(0.01));
  }
  // The fit's own predicted ball error is of the whole covariance, the unfitted joints' twist
  // included: a little larger.
  double sum = 0, fitted_sum = 0;
  for (double e : predictedBallErrors(at, joint, samples)) sum += e * e;
  for (double e : predicted) fitted_sum += e * e;
  CHECK(fit.predicted_ball_error_rms_mm == Approx(std::sqrt(sum / predicted.size())));
  CHECK(sum > fitted_sum);
}
