#include <catch2/catch.hpp>

#include "cli_helpers.hpp"

#include <robocal/formats/model_json.hpp>
#include <robocal/formats/samples_csv.hpp>
#include <robocal/kinematics/kinematics.hpp>

#include <nlohmann/json.hpp>

using namespace robocal;
using namespace robocal::test;
using Catch::Matchers::Contains;

TEST_CASE("robocal simulate writes samples and a truth that read back and agree") {
  TempDir dir;
  const auto r = runRobocal("simulate --model " + kModel + " --seed 3 --noise-mm 0 " +
                            "--connections B1C1,B3C2 --points-per-shell 40 --out " +
                            (dir / "s.csv") + " --truth-out " + (dir / "t.json"));
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  const auto samples = loadSamplesFile(dir / "s.csv");
  const Model truth = loadModelFile(dir / "t.json");
  const Model nominal = loadModelFile(kModel);
  REQUIRE(samples.size() <= 80);
  REQUIRE(samples.size() >= 70);
  CHECK(samples.front().ball_index == 0);
  CHECK(samples.back().ball_index == 2);
  CHECK(samples.back().chuck_index == 1);
  CHECK(samples.back().shell == 2);

  // Noise-free lengths are the truth's distances; the nominal's differ (the truth is perturbed).
  const Kinematics true_kin(truth), nominal_kin(nominal);
  double worst_truth = 0, worst_nominal = 0, worst_radius = 0;
  for (const Sample& s : samples) {
    const auto& ball = truth.balls_mm[s.ball_index];
    const auto& chuck = truth.chucks_mm[s.chuck_index];
    worst_truth = std::max(worst_truth,
                           std::abs(true_kin.barLength(s.joints_deg, ball, chuck) - s.length_mm));
    worst_nominal = std::max(
        worst_nominal, std::abs(nominal_kin.barLength(s.joints_deg, ball, chuck) - s.length_mm));
    worst_radius =
        std::max(worst_radius, std::abs(nominal_kin.barLength(s.joints_deg, ball, chuck) - 150));
  }
  CHECK(worst_truth < 1e-5);
  CHECK(worst_nominal > 0.05);
  CHECK(worst_radius < 1e-5);  // poses put the nominal ball on the default 150 mm shell
  // Every one of the 54 parameters was perturbed.
  CHECK((toParams(truth) - toParams(nominal)).cwiseAbs().minCoeff() > 0);
}

TEST_CASE("robocal simulate with noise: residuals against the truth have the asked sigma") {
  TempDir dir;
  const auto r = runRobocal("simulate --model " + kModel + " --seed 4 --noise-mm 0.084 " +
                            "--out " + (dir / "s.csv") + " --truth-out " + (dir / "t.json"));
  REQUIRE(r.exit_code == 0);
  const auto samples = loadSamplesFile(dir / "s.csv");
  const Model truth = loadModelFile(dir / "t.json");
  const Kinematics kin(truth);
  double sum2 = 0;
  for (const Sample& s : samples) {
    const double e = s.length_mm - kin.barLength(s.joints_deg, truth.balls_mm[s.ball_index],
                                                 truth.chucks_mm[s.chuck_index]);
    sum2 += e * e;
  }
  CHECK(samples.size() >= 780);  // nine shells of 90, a few grid points unreachable
  CHECK(std::sqrt(sum2 / samples.size()) == Approx(0.084).epsilon(0.08));
}

TEST_CASE("robocal identify --json reports rank 36 for all, 33 for one ball") {
  auto all = runRobocal("identify --model " + kModel + " --connections all --json");
  REQUIRE(all.exit_code == 0);
  const auto j = nlohmann::json::parse(all.output);
  CHECK(j["rank"] == 36);
  CHECK(j["parameters"] == 54);
  CHECK(j["expected"] == 36);
  CHECK(j["redundant"].size() == 18);
  auto one = runRobocal("identify --model " + kModel + " --connections B1C1,B1C2,B1C3 --json");
  REQUIRE(one.exit_code == 0);
  CHECK(nlohmann::json::parse(one.output)["rank"] == 33);
}

TEST_CASE("robocal identify --table covers every combination of connections") {
  auto r = runRobocal("identify --model " + kModel + " --table --json --points-per-shell 40");
  REQUIRE(r.exit_code == 0);
  const auto j = nlohmann::json::parse(r.output);
  CHECK(j["combinations"].size() == 511);
  CHECK(j["six_of_nine"]["total"] == 84);
  CHECK(j["paper_rows"][3]["rank"] == 36);
}

TEST_CASE("robocal commands reject bad input with a clear message") {
  TempDir dir;
  auto r = runRobocal("simulate --model /nonexistent.json");
  CHECK(r.exit_code != 0);
  CHECK_THAT(r.output, Contains("/nonexistent.json: cannot open"));
  r = runRobocal("simulate --model " + kModel + " --connections B4C1 --out " + (dir / "s.csv"));
  CHECK(r.exit_code != 0);
  CHECK_THAT(r.output, Contains("bad connection 'B4C1'"));
  r = runRobocal("identify --model " + kModel + " --bogus");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("unknown option --bogus"));
  r = runRobocal("simulate --model " + kModel + " --noise-mm abc");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("--noise-mm: 'abc' is not a number"));
  // robocal plan --compliance needs the model's load, and designs a calibration, not a check.
  r = runRobocal("plan --compliance --quiet --model " ROBOCAL_SOURCE_DIR
                 "/config/rx160.json --cell " ROBOCAL_SOURCE_DIR "/config/cell-rx160.json --out " +
                 (dir / "p.json"));
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("rx160.json: --compliance needs the model's \"compliance\" load"));
  r = runRobocal("plan --check --compliance --model " + kModel +
                 " --cell " ROBOCAL_SOURCE_DIR "/config/cell.json");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("a health check is not fitted"));
  r = runRobocal("frobnicate");
  CHECK(r.exit_code == 2);
}
