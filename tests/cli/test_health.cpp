// robocal health (docs/health-check.md): the whole offline check as a user runs it: calibrate a
// simulated robot, plan the check with the calibrated model, simulate the check run, judge it.
#include <catch2/catch.hpp>

#include "cli_helpers.hpp"

#include <robocal/formats/model_json.hpp>

#include <nlohmann/json.hpp>

using namespace robocal;
using namespace robocal::test;
using Catch::Matchers::Contains;

namespace {

const std::string kCell = ROBOCAL_SOURCE_DIR "/config/cell.json";

// The calibrated model cal.json of the true robot t.json (nine shells at 0 and at 150 mm), and
// the check plan check.json made with it.
void calibrateAndPlan(const TempDir& dir) {
  REQUIRE(runRobocal("simulate --model " + kModel + " --seed 3 --points-per-shell 40 --out " +
                     (dir / "s0.csv") + " --truth-out " + (dir / "t.json"))
              .exit_code == 0);
  REQUIRE(runRobocal("simulate --model " + kModel + " --truth " + (dir / "t.json") +
                     " --seed 4 --points-per-shell 40 --extension-mm 150 --first-shell 10 --out " +
                     (dir / "s1.csv"))
              .exit_code == 0);
  REQUIRE(runRobocal("solve --model " + kModel + " " + (dir / "s0.csv") + " " + (dir / "s1.csv") +
                     " --out " + (dir / "cal.json"))
              .exit_code == 0);
  const auto plan = runRobocal("plan --check --quiet --model " + (dir / "cal.json") + " --cell " +
                               kCell + " --out " + (dir / "check.json"));
  INFO(plan.output);
  REQUIRE(plan.exit_code == 0);
  CHECK_THAT(plan.output, Contains("forecast: none"));
  REQUIRE(runRobocal("check-plan --model " + (dir / "cal.json") + " --cell " + kCell + " " +
                     (dir / "check.json"))
              .exit_code == 0);
}

// The check run's samples of the robot `truth` (a model file) at the check plan's points.
std::string checkRun(const TempDir& dir, const std::string& truth, const std::string& name) {
  const auto r = runRobocal("simulate --model " + kModel + " --truth " + truth + " --plan " +
                            (dir / "check.json") + " --seed 77 --out " + (dir / name));
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  return dir / name;
}

}  // namespace

TEST_CASE("robocal health: PASS on the unchanged robot, FAIL naming a moved joint, WARN between") {
  TempDir dir;
  calibrateAndPlan(dir);
  const std::string same = checkRun(dir, dir / "t.json", "same.csv");
  const std::string base = "health --model " + (dir / "cal.json") + " ";

  const auto pass = runRobocal(base + same);
  INFO(pass.output);
  CHECK(pass.exit_code == 0);
  CHECK_THAT(pass.output, Contains("health check: PASS"));
  CHECK_THAT(pass.output, Contains("30 on B1C2,B2C3, extension 75 mm"));
  CHECK_THAT(pass.output, Contains("calibration: the active model's fit RMS"));

  // Joint 2's zero moved by 0.05 deg (a motor swap, a slipped encoder).
  Model moved = loadModelFile(dir / "t.json");
  moved.joints[1].offset_deg += 0.05;
  saveModelFile(dir / "t2.json", moved);
  const std::string changed = checkRun(dir, dir / "t2.json", "changed.csv");
  const auto fail = runRobocal(base + changed);
  INFO(fail.output);
  CHECK(fail.exit_code == 5);
  CHECK_THAT(fail.output, Contains("health check: FAIL"));
  CHECK_THAT(fail.output, Contains("J2.offset +0.0"));

  const auto json = runRobocal(base + changed + " --json");
  REQUIRE(json.exit_code == 5);
  const auto j = nlohmann::json::parse(json.output);
  CHECK(j["status"] == "fail");
  CHECK(j["samples"] == 30);
  CHECK(j["rms_ratio"].get<double>() > 1.5);
  REQUIRE_FALSE(j["moved"].empty());
  CHECK(j["moved"][0]["name"] == "J2.offset");

  // Thresholds from the command line: the unchanged robot's ratio (about 1) between them.
  const auto warn = runRobocal(base + same + " --warn-ratio 0.5 --fail-ratio 3");
  INFO(warn.output);
  CHECK(warn.exit_code == 4);
  CHECK_THAT(warn.output, Contains("health check: WARN"));
  // A baseline check's RMS as the reference.
  const auto baseline = runRobocal(base + same + " --baseline-mm 0.06 --json");
  CHECK(nlohmann::json::parse(baseline.output)["reference"] == "baseline");
}

TEST_CASE("robocal health: bad usage and unreadable input") {
  TempDir dir;
  CHECK(runRobocal("health --model " + kModel).exit_code == 2);
  CHECK(runRobocal("health").exit_code == 2);
  CHECK(runRobocal("health --model " + kModel + " " + (dir / "missing.csv")).exit_code == 1);
  const auto ratios =
      runRobocal("health --model " + kModel + " x.csv --warn-ratio 2 --fail-ratio 1.5");
  CHECK(ratios.exit_code == 2);
  CHECK_THAT(ratios.output, Contains("--fail-ratio"));
  const auto help = runRobocal("health --help");
  CHECK(help.exit_code == 0);
  CHECK_THAT(help.output, Contains("exit status: 0 PASS, 4 WARN, 5 FAIL"));
}
