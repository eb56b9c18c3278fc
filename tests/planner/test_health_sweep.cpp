// The five-minute health check end to end in the math (planner/health_plan.hpp, solver/health.hpp,
// docs/health-check.md "Measured"): a perturbed true robot calibrated from the reference cell's
// grid plan (nine connections at 0 and 150 mm, 1,714 points, as the check's design assumes), then
// the check plan's own 30 points measured on it unchanged (at the calibration's noise and at 1.5
// times it) and with one parameter moved by the size the check is designed for: 0.02 deg on
// joints 1-3, 0.05 deg on joints 4-6, 0.1 mm on a link translation.
// The visible test runs 20 seeds on a few of the changes; `[.health-sweep]` all of them on 200
// seeds at two noise levels and prints the table of docs/health-check.md.
#include <catch2/catch.hpp>

#include "fixtures.hpp"

#include <robocal/kinematics/units.hpp>
#include <robocal/planner/health_plan.hpp>
#include <robocal/sim/measurements.hpp>
#include <robocal/solver/calibrate.hpp>
#include <robocal/solver/health.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

using namespace robocal;

namespace {

using test::gridCell;
using test::nominal;

const Plan& checkPlanOfDefaultCell() {
  static const Plan p = planHealthCheck(nominal(), gridCell());
  return p;
}

std::vector<Sample> withNoise(std::vector<Sample> samples, double noise_mm, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0, noise_mm);
  for (Sample& s : samples) s.length_mm += noise(rng);
  return samples;
}

// The calibrated model of `truth` from the reference cell's grid plan, with the provenance RMS
// and the covariance a written model carries.
Model calibrate(const Model& truth, double noise_mm, std::mt19937_64& rng) {
  const Model& nom = nominal();
  static const Plan grid = planCell(nom, gridCell());
  const SolveResult fit = solveCalibration(nom, withNoise(planSamples(truth, grid), noise_mm, rng));
  Model active = withParams(nom, fit.params);
  active.provenance = ModelProvenance{};
  active.provenance->rms_mm = fit.after.rms_mm;
  active.provenance->samples = fit.residuals.size();
  active.covariance = fit.covariance;  // as a written model carries it
  return active;
}

// One case of the sweep: a parameter moved by `change` (interface units; none: unchanged), the
// check read at `noise_factor` times the calibration's noise.
struct Case {
  std::string name;  // the parameter's, or "unchanged"
  int index = -1;
  double change = 0;
  double noise_factor = 1;
};

struct Tally {
  int pass = 0, warn = 0, fail = 0;
  int named = 0;       // the moved parameter named first
  int equivalent = 0;  // or one the data cannot tell from it
  int named_something = 0;
  std::vector<double> ratios;
};

Model moved(const Model& truth, const Case& c) {
  if (c.index < 0) return truth;
  ParamVector p = toParams(truth);
  p[c.index] += paramKind(c.index) == ParamKind::kTranslation ? c.change : degToRad(c.change);
  return withParams(truth, p);
}

std::vector<Case> allCases() {
  std::vector<Case> cases = {{"unchanged", -1, 0, 1}, {"unchanged", -1, 0, 1.5}};
  for (int j = 0; j < kJointCount; ++j) {
    const int i = jointParamIndex(j);
    cases.push_back({paramName(i), i, j < 3 ? kHealthCheckJoint13Deg : kHealthCheckJoint46Deg, 1});
  }
  for (int link = 0; link < kLinkCount; ++link)
    for (int axis = 0; axis < 3; ++axis) {
      const int i = linkParamIndex(link) + axis;
      cases.push_back({paramName(i), i, kHealthCheckTranslationMm, 1});
    }
  return cases;
}

std::vector<Tally> sweep(const std::vector<Case>& cases, int seeds, double noise_mm) {
  const Plan& plan = checkPlanOfDefaultCell();
  std::vector<Tally> tallies(cases.size());
  for (int seed = 1; seed <= seeds; ++seed) {
    std::mt19937_64 rng(1000 + seed);
    const Model truth = perturbModel(nominal(), PerturbationSigmas{}, rng);
    const Model active = calibrate(truth, noise_mm, rng);
    for (size_t k = 0; k < cases.size(); ++k) {
      const Case& c = cases[k];
      const HealthVerdict v = assessHealth(
          active, withNoise(planSamples(moved(truth, c), plan), noise_mm * c.noise_factor, rng));
      Tally& t = tallies[k];
      t.pass += v.status == HealthStatus::kPass;
      t.warn += v.status == HealthStatus::kWarn;
      t.fail += v.status == HealthStatus::kFail;
      t.named_something += !v.moved.empty();
      t.ratios.push_back(v.rms_ratio);
      if (!v.moved.empty()) {
        const ParameterChange& first = v.moved.front();
        t.named += first.name == c.name;
        t.equivalent += first.name == c.name ||
                        std::find(first.equivalent.begin(), first.equivalent.end(), c.name) !=
                            first.equivalent.end();
      }
    }
  }
  return tallies;
}

void printTable(const std::vector<Case>& cases, const std::vector<Tally>& tallies, int seeds,
                double noise_mm) {
  const Plan& plan = checkPlanOfDefaultCell();
  std::printf(
      "short health check: %d points on %zu shells, %.1f min of robot time + %.0f min of the "
      "operator's = %.1f min; %d seeds, calibration noise %.3f mm\n",
      plan.summary.points, plan.shells.size(), plan.summary.duration_s / 60,
      kHealthCheckOperatorMinPerShell * static_cast<double>(plan.shells.size()),
      plan.summary.duration_s / 60 +
          kHealthCheckOperatorMinPerShell * static_cast<double>(plan.shells.size()),
      seeds, noise_mm);
  std::printf(
      "| moved | by | check noise | RMS ratio min / median / max | PASS | WARN | FAIL | named "
      "first | or an equivalent |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  for (size_t k = 0; k < cases.size(); ++k) {
    const Case& c = cases[k];
    Tally t = tallies[k];
    std::sort(t.ratios.begin(), t.ratios.end());
    char by[32] = "";
    if (c.index >= 0)
      std::snprintf(by, sizeof by, "%g %s", c.change,
                    paramKind(c.index) == ParamKind::kTranslation ? "mm" : "deg");
    std::printf("| %s | %s | %.1fx | %.2f / %.2f / %.2f | %d | %d | %d | %d | %d |\n",
                c.name.c_str(), by, c.noise_factor, t.ratios.front(), t.ratios[t.ratios.size() / 2],
                t.ratios.back(), t.pass, t.warn, t.fail, c.index < 0 ? t.named_something : t.named,
                c.index < 0 ? 0 : t.equivalent);
  }
}

}  // namespace

TEST_CASE(
    "the short check, 20 seeds: unchanged robots pass, also on a noisier day, and the design's "
    "changes fail and are named") {
  const Case cases[] = {
      {"unchanged", -1, 0, 1},
      {"unchanged", -1, 0, 1.5},
      {"J2.offset", jointParamIndex(1), kHealthCheckJoint13Deg, 1},
      {"J5.offset", jointParamIndex(4), kHealthCheckJoint46Deg, 1},
      {"J6.offset", jointParamIndex(5), kHealthCheckJoint46Deg, 1},
      {"L2.x", linkParamIndex(2), kHealthCheckTranslationMm, 1},
  };
  const std::vector<Case> list(std::begin(cases), std::end(cases));
  const int seeds = 20;
  // The main job's noise (cellsim's bar, about 0.035 mm): the check's design sizes are for it.
  const std::vector<Tally> t = sweep(list, seeds, 0.035);
  printTable(list, t, seeds, 0.035);
  CHECK(t[0].pass >= seeds - 1);
  CHECK(t[1].pass >= seeds - 1);
  CHECK(t[0].named_something <= 1);
  CHECK(t[1].named_something <= 1);
  for (size_t k = 2; k < list.size(); ++k) {
    INFO(list[k].name);
    // Joint 6, the weakest signature, is seen in about 98 % of robots and named in 95 %.
    const int slack = list[k].name == "J6.offset" ? 1 : 0;
    CHECK(t[k].fail >= seeds - 1 - slack);
    CHECK(t[k].equivalent >= seeds - 2 - slack);
  }
}

TEST_CASE("unchanged robots read 1.5 times as noisy as their calibration: about 1 % named",
          "[heavy]") {
  // The check's own level, estimated from its 30 residuals, scatters by 13 %. Judged at it with
  // the normal's significance, 11 of these 300 robots (22 of 1,000) were named something; with
  // Student's t for the check's degrees of freedom, 2 (5 of 1,000).
  const std::vector<Case> cases = {{"unchanged", -1, 0, 1.5}};
  const int seeds = 300;
  const std::vector<Tally> t = sweep(cases, seeds, 0.035);
  CHECK(t[0].named_something <= 5);
  CHECK(t[0].fail <= 5);
}

TEST_CASE("the short check's sweep: every joint offset and link translation, 200 seeds",
          "[.health-sweep]") {
  const std::vector<Case> cases = allCases();
  for (double noise_mm : {0.035, 0.084}) {
    const int seeds = 200;
    printTable(cases, sweep(cases, seeds, noise_mm), seeds, noise_mm);
  }
}
