#include <catch2/catch.hpp>

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/units.hpp>
#include <robocal/robot/puma560.hpp>
#include <robocal/sim/measurements.hpp>
#include <robocal/solver/assessment.hpp>
#include <robocal/solver/calibrate.hpp>

#include "fit_fixtures.hpp"

using namespace robocal;
using namespace robocal::test;

namespace {

double ballErrorRms(const Model& a, const Model& b, const std::vector<Sample>& samples) {
  const Kinematics ka(a), kb(b);
  double sum = 0;
  for (const Sample& s : samples) {
    const auto& ball = a.balls_mm[s.ball_index];
    sum +=
        (ka.ballPosition(s.joints_deg, ball) - kb.ballPosition(s.joints_deg, ball)).squaredNorm();
  }
  return std::sqrt(sum / samples.size());
}

}  // namespace

TEST_CASE("LM converges from the nominal to a truth several mm and tenths of a degree away") {
  const Model nominal = puma560NominalModel();
  const Model truth = perturbed(5.0, 21);  // 1 mm translations, 0.1-0.25 deg angles
  const Shells shells = planShells(nominal, "all", 0, 60, 1);
  const auto samples = measure(truth, shells, 0.0, 2);
  const SolveResult fit = solveCalibration(nominal, samples);
  CHECK(fit.identifiability.rank == 36);
  CHECK(fit.free_params.size() == 36);
  CHECK(fit.before.rms_mm > 1.0);
  CHECK(fit.after.rms_mm < 1e-6);
  CHECK(fit.covariance.allFinite());
  // Redundant parameters never move from their start values.
  for (int i : fit.identifiability.redundant) CHECK(fit.params[i] == toParams(nominal)[i]);
  // The fitted model puts the balls where the truth has them, also on other (larger) shells.
  const auto validation = measure(truth, planShells(nominal, "all", 150, 40, 3), 0.0, 4);
  CHECK(ballErrorRms(withParams(nominal, fit.params), truth, validation) < 1e-4);
}

TEST_CASE("with noise the fit reaches the noise floor and predicts held-out shells") {
  const Model nominal = puma560NominalModel();
  const Model truth = perturbed(1.0, 31);
  const double sigma = 0.084;
  const auto samples = measure(truth, planShells(nominal, "all", 0, 90, 5), sigma, 6);
  const auto held_out = measure(truth, planShells(nominal, "all", 150, 90, 7), sigma, 8);
  const SolveResult fit = solveCalibration(nominal, samples);
  const double m = static_cast<double>(samples.size());
  const double expected_rms = sigma * std::sqrt((m - 36) / m);
  CHECK(fit.after.rms_mm == Approx(expected_rms).epsilon(0.05));
  CHECK(fit.sigma_mm == Approx(sigma).epsilon(0.08));
  const auto v = residualStats(sampleResiduals(withParams(nominal, fit.params), held_out));
  CHECK(v.rms_mm <= 1.10 * sigma);
  CHECK(fit.condition_number > 1);
  CHECK(fit.o3 > 0);
}

TEST_CASE("the reported covariance predicts the real ball-position error (50 noise draws)") {
  const Model nominal = puma560NominalModel();
  const Model truth = perturbed(1.0, 41);
  const Shells shells = planShells(nominal, "all", 0, 90, 9);
  const auto validation = measure(truth, planShells(nominal, "all", 150, 30, 10), 0.0, 11);
  double actual = 0, predicted = 0;
  const int draws = 50;
  for (int d = 0; d < draws; ++d) {
    const auto samples = measure(truth, shells, 0.084, 100 + d);
    const SolveResult fit = solveCalibration(nominal, samples);
    const Model calibrated = withParams(nominal, fit.params);
    actual += std::pow(ballErrorRms(calibrated, truth, validation), 2);
    double pred = 0;
    for (double e : predictedBallErrors(calibrated, fit.covariance, validation)) pred += e * e;
    predicted += pred / validation.size();
  }
  // Mean squared ball-position error against what sigma^2 (J^T J)^+ predicts: within 15%.
  CHECK(actual / draws == Approx(predicted / draws).epsilon(0.15));
}

TEST_CASE("rank-deficient data: the identifiable part is solved and the rank reported") {
  const Model nominal = puma560NominalModel();
  const Model truth = perturbed(1.0, 51);
  SECTION("one shell only") {
    const auto samples = measure(truth, planShells(nominal, "B2C3", 0, 90, 12), 0.0, 13);
    const SolveResult fit = solveCalibration(nominal, samples);
    CHECK(fit.identifiability.rank < 36);
    CHECK(fit.identifiability.rank == static_cast<int>(fit.free_params.size()));
    CHECK(fit.params.allFinite());
    CHECK(fit.after.rms_mm < 0.01 * fit.before.rms_mm);
  }
  SECTION("every sample at one pose") {
    auto samples = measure(truth, planShells(nominal, "B1C1", 0, 1, 14), 0.0, 15);
    REQUIRE(samples.size() == 1);
    samples.resize(20, samples.front());
    const SolveResult fit = solveCalibration(nominal, samples);
    CHECK(fit.identifiability.rank == 1);
    CHECK(fit.params.allFinite());
    CHECK(fit.covariance.allFinite());
    CHECK(fit.after.rms_mm < 1e-6);
  }
}

TEST_CASE("converges when the nominal is 20 mm off") {
  const Model truth = puma560NominalModel();
  Model start = truth;
  start.links[2].x_mm += 20.0;  // the upper arm 20 mm too long
  const auto samples = measure(truth, planShells(truth, "all", 0, 50, 16), 0.0, 17);
  const SolveResult fit = solveCalibration(start, samples);
  CHECK(fit.before.rms_mm > 5.0);
  CHECK(fit.after.rms_mm < 1e-6);
  CHECK(fit.params[linkParamIndex(2)] == Approx(truth.links[2].x_mm).margin(1e-6));
}

TEST_CASE("an outlier is found by its residual") {
  const Model nominal = puma560NominalModel();
  const Model truth = perturbed(1.0, 61);
  auto samples = measure(truth, planShells(nominal, "all", 0, 60, 18), 0.084, 19);
  samples[123].length_mm += 1.5;  // a bumped bar
  const SolveResult fit = solveCalibration(nominal, samples);
  const auto outliers = findOutliers(fit.residuals, 4.0);
  REQUIRE(outliers.size() >= 1);
  CHECK(std::any_of(outliers.begin(), outliers.end(),
                    [](const Outlier& o) { return o.index == 123; }));
  CHECK(outliers.size() <= 3);
}

TEST_CASE("no samples is a clear error") {
  CHECK_THROWS_AS(solveCalibration(puma560NominalModel(), {}), std::invalid_argument);
}

TEST_CASE("the assessment: the fit's parameters, uncertainties and shells in interface units") {
  const Model nominal = puma560NominalModel();
  const Model truth = perturbed(1.0, 71);
  const auto samples = measure(truth, planShells(nominal, "all", 0, 60, 20), 0.084, 21);
  const FitAssessment a = assessFit(nominal, samples);
  CHECK(a.problems.empty());
  CHECK(a.samples.size() == samples.size());
  CHECK(toParams(a.calibrated).isApprox(a.fit.params, 1e-14));
  CHECK(a.connections.size() == 9);
  REQUIRE(a.parameters.size() == kParamCount);
  int estimated = 0;
  for (const ParameterRow& p : a.parameters) {
    const int i = p.index;
    CHECK(p.nominal == paramInterfaceValue(toParams(nominal), i));
    CHECK(p.calibrated == paramInterfaceValue(a.fit.params, i));
    const bool free = std::count(a.fit.free_params.begin(), a.fit.free_params.end(), i) == 1;
    CHECK(p.estimated == free);
    estimated += p.estimated;
    const double scale = paramKind(i) == ParamKind::kAngle ? kDegPerRad : 1.0;
    CHECK(p.sigma == Approx(std::sqrt(a.fit.covariance(i, i)) * scale));
    if (!p.estimated) CHECK(p.change() == 0.0);
  }
  CHECK(estimated == 36);
  REQUIRE(a.shells.shells.size() == 9);
  size_t counted = 0;
  for (const ShellResiduals& s : a.shells.shells) counted += s.stats.count;
  CHECK(counted == samples.size());
  CHECK(a.predicted_ball_error_rms_mm > 0);
  CHECK(a.predicted_ball_error_rms_mm < a.fit.before.rms_mm);
}

TEST_CASE("the assessment says why a fit is not usable as a calibration") {
  const Model nominal = puma560NominalModel();
  const Model truth = perturbed(1.0, 72);
  SECTION("below the expected rank") {
    const auto samples = measure(truth, planShells(nominal, "B1C1,B2C2", 0, 60, 22), 0.084, 23);
    const FitAssessment a = assessFit(nominal, samples);
    REQUIRE(a.problems.size() == 1);
    CHECK_THAT(a.problems[0], Catch::Contains("rank " + std::to_string(a.fit.identifiability.rank) +
                                              " of the 36") &&
                                  Catch::Contains("(B1C1,B2C2)"));
  }
  SECTION("a predicted error above the nominal's") {
    const auto samples = measure(truth, planShells(nominal, "all", 0, 6, 24), 1.5, 25);
    const FitAssessment a = assessFit(nominal, samples);
    CHECK(a.fit.identifiability.rank == 36);
    // 54 samples for 36 parameters and 1.5 mm of noise also fail the other rules (verdict.hpp).
    CHECK_THAT(a.problems.back(), Catch::Contains("exceeds the nominal model's error"));
  }
}

TEST_CASE("held-out samples are predicted by the given model, or by the fit") {
  const Model nominal = puma560NominalModel();
  const Model truth = perturbed(1.0, 73);
  const auto samples = measure(truth, planShells(nominal, "all", 0, 40, 26), 0.084, 27);
  const auto later = measure(truth, planShells(nominal, "all", 150, 20, 28), 0.084, 29);
  AssessOptions options;
  options.validation = HeldOutSamples{later, nominal, "set 2 predicted by the nominal"};
  FitAssessment a = assessFit(nominal, samples, options);
  REQUIRE(a.validation);
  CHECK(a.validation->residuals == sampleResiduals(nominal, later));
  CHECK(a.validation->description == "set 2 predicted by the nominal");
  options.validation->predictor.reset();
  a = assessFit(nominal, samples, options);
  CHECK(a.validation->residuals == sampleResiduals(a.calibrated, later));
  CHECK(a.validation->shells.shells.size() == 9);
}

TEST_CASE("the shell table names the worst shells and the one that stands out") {
  std::vector<Sample> samples;
  std::vector<double> r;
  for (int shell = 1; shell <= 5; ++shell)
    for (int k = 0; k < 10; ++k) {
      Sample s;
      s.shell = shell;
      s.ball_index = shell % 3;
      samples.push_back(s);
      const double size = shell == 3 ? 0.067 : 0.014 + 0.004 * shell;  // 0.018 ... 0.034
      r.push_back(k % 2 ? size : -size);
    }
  const ShellTable t = shellTable(samples, Eigen::Map<Eigen::VectorXd>(r.data(), r.size()));
  REQUIRE(t.shells.size() == 5);
  CHECK(t.shells[2].shell == 3);
  CHECK(t.shells[2].stats.rms_mm == Approx(0.067));
  CHECK(t.shells[2].stands_out);
  for (int k : {0, 1, 3, 4}) CHECK_FALSE(t.shells[k].stands_out);
  CHECK(t.worst == std::vector<int>{2, 4, 3});
}

TEST_CASE("the identifiability cache gives the uncached result, and only for the same plan") {
  const Model nominal = puma560NominalModel();
  const Model truth = perturbed(1.0, 81);
  const Shells shells = planShells(nominal, "all", 0, 40, 30);
  const auto samples = measure(truth, shells, 0.084, 31);
  const SolveResult plain = solveCalibration(nominal, samples);

  IdentifiabilityCache cache;
  SolveOptions options;
  options.identifiability_cache = &cache;
  const auto sameFit = [](const SolveResult& a, const SolveResult& b) {
    CHECK(a.params == b.params);
    CHECK(a.free_params == b.free_params);
    CHECK(a.identifiability.rank == b.identifiability.rank);
    CHECK(a.identifiability.redundant == b.identifiability.redundant);
    CHECK(a.identifiability.singular_values == b.identifiability.singular_values);
    CHECK(a.covariance == b.covariance);
    CHECK(a.iterations == b.iterations);
  };
  const SolveResult first = solveCalibration(nominal, samples, options);
  CHECK(cache.misses() == 1);
  CHECK(cache.hits() == 0);
  sameFit(first, plain);
  const SolveResult again = solveCalibration(nominal, samples, options);
  CHECK(cache.hits() == 1);
  sameFit(again, plain);

  SECTION("new lengths at the same poses reuse the analysis") {
    const auto remeasured = measure(truth, shells, 0.084, 32);
    const SolveResult refit = solveCalibration(nominal, remeasured, options);
    CHECK(cache.hits() == 2);
    sameFit(refit, solveCalibration(nominal, remeasured));
  }
  SECTION("another plan is analysed afresh, not given the stored analysis") {
    // Two shells identify fewer parameters than nine: a stale analysis would show.
    const auto other = measure(truth, planShells(nominal, "B1C1,B2C2", 0, 40, 33), 0.0, 34);
    const SolveResult fresh = solveCalibration(nominal, other);
    REQUIRE(fresh.identifiability.rank < plain.identifiability.rank);
    const SolveResult cached = solveCalibration(nominal, other, options);
    CHECK(cache.hits() == 1);
    CHECK(cache.misses() == 2);
    sameFit(cached, fresh);
  }
  SECTION("one moved pose, or another start point, is a different plan") {
    auto moved = samples;
    moved[7].joints_deg[3] += 1e-9;
    solveCalibration(nominal, moved, options);
    CHECK(cache.hits() == 1);
    CHECK(cache.misses() == 2);
    Model start = nominal;
    start.links[2].x_mm += 0.5;
    sameFit(solveCalibration(start, samples, options), solveCalibration(start, samples));
    CHECK(cache.hits() == 1);
    CHECK(cache.misses() == 3);
    Model other_balls = nominal;
    other_balls.balls_mm[1].x() += 0.1;
    solveCalibration(other_balls, samples, options);
    CHECK(cache.misses() == 4);
  }
  SECTION("with a prior the cached analysis is the same as the uncached one") {
    options.prior_sigma = paramSigmas(1.0, 0.1, 0.1, 1e-3);
    SolveOptions uncached = options;
    uncached.identifiability_cache = nullptr;
    sameFit(solveCalibration(nominal, samples, options),
            solveCalibration(nominal, samples, uncached));
    CHECK(cache.hits() == 2);
  }
}
