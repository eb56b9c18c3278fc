// The verdict on a fit (verdict.hpp): each rule fires on the data that should fail it, with the
// cause and the fix in words, and stays quiet on an ordinary calibration.
#include <catch2/catch.hpp>

#include <robocal/robot/puma560.hpp>
#include <robocal/sim/measurements.hpp>
#include <robocal/solver/assessment.hpp>
#include <robocal/solver/verdict.hpp>

#include "fit_fixtures.hpp"

#include <algorithm>
#include <map>
#include <random>
#include <tuple>

using namespace robocal;
using namespace robocal::test;

namespace {

bool anyContains(const std::vector<std::string>& problems, const std::string& text) {
  return std::any_of(problems.begin(), problems.end(),
                     [&](const std::string& p) { return p.find(text) != std::string::npos; });
}

}  // namespace

TEST_CASE("verdict: an ordinary calibration has no problems, and each bad input has its own") {
  const Model nominal = puma560NominalModel();
  const Model truth = perturbed(1.0, 81);
  std::vector<Sample> samples = measure(truth, planShells(nominal, "all", 0, 30, 82), 0.084, 83);
  for (size_t i = 0; i < samples.size(); ++i) {
    samples[i].source = "samples.csv";
    samples[i].source_line = static_cast<int>(i) + 2;
  }
  REQUIRE(assessFit(nominal, samples).problems.empty());

  SECTION("joints in radians") {
    for (Sample& s : samples) s.joints_deg *= M_PI / 180;
    const FitAssessment a = assessFit(nominal, samples);
    REQUIRE_FALSE(a.problems.empty());
    CHECK_THAT(a.problems[0], Catch::Contains("as if in radians") &&
                                  Catch::Contains("samples.csv:2") && Catch::Contains("57.2958"));
    CHECK(anyContains(a.problems, "far above a ball-bar's noise"));
  }
  SECTION("lengths in metres") {
    for (Sample& s : samples) s.length_mm *= 1e-3;
    const FitAssessment a = assessFit(nominal, samples);
    REQUIRE_FALSE(a.problems.empty());
    CHECK_THAT(a.problems[0], Catch::Contains("as if in metres") && Catch::Contains("x 1000"));
  }
  SECTION("gross outliers kept, then dropped") {
    samples[40].length_mm += 2.0;
    samples[200].length_mm += 25.0;
    AssessOptions options;
    FitAssessment a = assessFit(nominal, samples, options);
    CHECK(a.outliers.size() >= 2);
    CHECK(anyContains(a.problems, "kept in the fit (the worst +2"));
    CHECK(anyContains(a.problems, "samples.csv:202"));
    options.drop_outliers = true;
    a = assessFit(nominal, samples, options);
    CHECK(a.outliers_dropped);
    CHECK(a.problems.empty());
  }
  SECTION("noise far above a ball-bar's") {
    const auto noisy = measure(truth, planShells(nominal, "all", 0, 30, 82), 1.0, 84);
    CHECK(anyContains(assessFit(nominal, noisy).problems, "far above a ball-bar's noise"));
  }
}

TEST_CASE("verdict: as many points as parameters fit anything and are refused") {
  const Model nominal = puma560NominalModel();
  const Model truth = perturbed(1.0, 85);
  // Five points a connection: 45 samples for 36 parameters, 9 degrees of freedom.
  const auto few = measure(truth, planShells(nominal, "all", 0, 5, 86), 0.084, 87);
  const FitAssessment a = assessFit(nominal, few);
  CHECK(anyContains(a.problems, "degrees of freedom"));
  CHECK(anyContains(a.problems, "measure at least " +
                                    std::to_string(2 * a.fit.identifiability.rank) + " points"));
  // Eight a connection: 72, twice the parameters, is enough redundancy for the rule.
  const auto enough = measure(truth, planShells(nominal, "all", 0, 8, 86), 0.084, 87);
  CHECK_FALSE(anyContains(assessFit(nominal, enough).problems, "degrees of freedom"));
}

TEST_CASE("verdict: units are judged from the data, not guessed from a few samples") {
  const Model nominal = puma560NominalModel();
  const auto samples = measure(nominal, planShells(nominal, "B1C1", 0, 30, 88), 0.0, 89);
  CHECK_FALSE(samplesUnitsProblem(nominal, samples));
  std::vector<Sample> radians(samples.begin(), samples.begin() + 9);
  for (Sample& s : radians) s.joints_deg *= M_PI / 180;
  CHECK_FALSE(samplesUnitsProblem(nominal, radians));  // 9 samples: too few to judge
  radians.push_back(radians.back());
  CHECK(samplesUnitsProblem(nominal, radians));
}

TEST_CASE("adequacy: backlash shows as a pattern of the approach, an ideal robot shows none") {
  const Model nominal = puma560NominalModel();
  Realism backlash = Realism::ideal();
  backlash.backlash_deg = {0.01, 0.01, 0.01, 0.01, 0.01, 0.01};
  int fired_ideal = 0, fired_backlash = 0;
  const int seeds = 5;
  for (int seed = 0; seed < seeds; ++seed) {
    const Model truth = perturbed(1.0, 90 + seed);
    const Shells shells = planShells(nominal, "all", 0, 40, 100 + seed);
    for (const bool with_backlash : {false, true}) {
      // The shells measured in order, each point reached from the previous one.
      std::mt19937_64 rng(200 + seed);
      RunTrack track;
      std::vector<Sample> samples;
      for (size_t i = 0; i < shells.requests.size(); ++i) {
        const auto s = measureShell(TrueRobot{truth, with_backlash ? backlash : Realism::ideal()},
                                    shells.requests[i], shells.poses[i], {0.084, 0}, rng, track);
        samples.insert(samples.end(), s.begin(), s.end());
      }
      const FitAssessment a = assessFit(nominal, samples);
      INFO("seed " << seed << (with_backlash ? " backlash: " : " ideal: ") << a.adequacy.summary());
      (with_backlash ? fired_backlash : fired_ideal) += !a.adequacy.ok;
      if (with_backlash && !a.adequacy.ok) {
        CHECK_THAT(a.adequacy.summary(), Catch::Contains("approach direction of joint"));
        CHECK(a.adequacy.unmodelled_mm > 0.01);
        CHECK(a.adequacy.unmodelled_bar_mm() == a.adequacy.unmodelled_mm);
      }
      if (a.adequacy.ok) CHECK(a.adequacy.unmodelled_bar_mm() == 0);
    }
  }
  CHECK(fired_backlash == seeds);
  CHECK(fired_ideal <= 1);
}

TEST_CASE(
    "adequacy: revisits measure the bar's noise, and a residual the noise cannot explain is "
    "found") {
  const Model nominal = puma560NominalModel();
  const Model truth = perturbed(1.0, 95);
  Shells shells = planShells(nominal, "all", 0, 40, 105);
  // Every fourth point measured again at the end of its shell: 10 revisits a shell.
  for (auto& poses : shells.poses) {
    const std::size_t n = poses.size();
    for (std::size_t i = 0; i < n; i += 4) poses.push_back(poses[i]);
  }
  const double noise_mm = 0.05;
  std::vector<Sample> samples = measure(truth, shells, noise_mm, 106);
  const FitAssessment plain = assessFit(nominal, samples);
  INFO(plain.adequacy.summary());
  REQUIRE(plain.adequacy.noise_mm);
  CHECK(plain.adequacy.revisited_places == 90);
  CHECK(plain.adequacy.noise_dof == 90);
  CHECK(*plain.adequacy.noise_mm == Approx(noise_mm).epsilon(0.3));
  CHECK_FALSE(plain.adequacy.lack_of_fit);
  CHECK(plain.adequacy.ok);
  CHECK_THAT(plain.adequacy.summary(), Catch::Contains("the bar's noise measured by 90 revisits"));

  // An error of each place that no pattern follows and no parameter absorbs (0.08 mm, the same
  // at a revisit): the residual outgrows the noise.
  std::mt19937_64 rng(107);
  std::normal_distribution<double> place_error(0.0, 0.08);
  std::map<std::tuple<int, double, double>, double> error_of;
  for (Sample& s : samples) {
    const auto key = std::make_tuple(s.shell, s.lat_deg, s.lon_deg);
    if (!error_of.count(key)) error_of[key] = place_error(rng);
    s.length_mm += error_of[key];
  }
  const FitAssessment worse = assessFit(nominal, samples);
  INFO(worse.adequacy.summary());
  CHECK(worse.adequacy.noise_mm.value_or(0) == Approx(noise_mm).epsilon(0.3));
  CHECK(worse.adequacy.lack_of_fit);
  CHECK_FALSE(worse.adequacy.ok);
  CHECK(worse.adequacy.fit_over_noise > worse.adequacy.fit_over_noise_limit);
  // What the model does not contain, from the residual's excess over the noise: about the 0.08
  // mm added (less what the parameters absorbed of it).
  CHECK(worse.adequacy.unmodelled_bar_mm() > 0.05);
  CHECK(worse.adequacy.unmodelled_bar_mm() < 0.1);
  CHECK(plain.adequacy.unmodelled_bar_mm() == 0);
  CHECK_THAT(worse.adequacy.summary(), Catch::Contains("x the bar's noise measured by 90"));
  // Far above the noise the revisits measured (1.5 times): not usable, with the reason and the fix.
  INFO(worse.adequacy.fit_over_noise);
  CHECK(worse.adequacy.fit_over_noise > 1.5);
  const auto refused = [](const FitAssessment& a) {
    for (const std::string& p : a.problems)
      if (p.find("revisited places measured") != std::string::npos) return true;
    return false;
  };
  CHECK(refused(worse));
  CHECK_FALSE(refused(plain));
  CHECK(plain.problems.empty());
  // The limit is the verdict's: raised past the ratio, the same fit is not refused for it.
  VerdictLimits lenient;
  lenient.max_fit_over_noise = worse.adequacy.fit_over_noise + 0.1;
  for (const std::string& p : fitProblems(worse, lenient))
    CHECK(p.find("revisited places measured") == std::string::npos);
}
