// The health check's plan (planner/health_plan.hpp, docs/health-check.md) and the plan file's
// purpose.
#include <catch2/catch.hpp>

#include "fixtures.hpp"

#include <robocal/formats/model_json.hpp>
#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/units.hpp>
#include <robocal/planner/cell_json.hpp>
#include <robocal/planner/check.hpp>
#include <robocal/planner/health_plan.hpp>
#include <robocal/planner/plan_json.hpp>
#include <robocal/sim/measurements.hpp>
#include <robocal/solver/calibrate.hpp>
#include <robocal/solver/health.hpp>

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>

using namespace robocal;

namespace {

using test::gridCell;
using test::kSource;
using test::nominal;

const Plan& checkPlanOfDefaultCell() {
  static const Plan p = planHealthCheck(nominal(), gridCell());
  return p;
}

std::string connectionsOf(const Plan& plan) {
  std::vector<Connection> c;
  for (const ShellPlan& s : plan.shells) c.push_back(s.connection);
  return connectionList(c);
}

std::string planErrorOf(const std::string& text) {
  try {
    parsePlan(text, "plan.json");
  } catch (const FormatError& e) {
    return e.what();
  }
  return "";
}

std::string robocalBinary() {
  if (const char* dir = std::getenv("ROBOCAL_BIN")) return std::string(dir) + "/robocal";
  return std::string(ROBOCAL_BINARY_DIR) + "/cli/robocal";
}

std::string tempPath(const std::string& name) {
  return std::string(ROBOCAL_BINARY_DIR) + "/test_health_plan_" + std::to_string(::getpid()) + "_" +
         name;
}

int runCommand(const std::string& command, std::string& output) {
  const std::string out_path = tempPath("cmd_output.txt");
  const int status = std::system((command + " > " + out_path + " 2>&1").c_str());
  std::ifstream in(out_path);
  std::stringstream text;
  text << in.rdbuf();
  output = text.str();
  std::remove(out_path.c_str());
  return status;
}

}  // namespace

TEST_CASE("the check's extension lies between the calibration's, never on one of them") {
  BarSettings bar;
  bar.nominal_length_mm = 150;
  bar.extension_lengths_mm = {0, 150};
  CHECK(healthCheckExtension(bar) == 75.0);
  bar.extension_lengths_mm = {150, 0};
  CHECK(healthCheckExtension(bar) == 75.0);
  bar.extension_lengths_mm = {0, 50, 150};  // the widest gap, 50 .. 150
  CHECK(healthCheckExtension(bar) == 100.0);
  bar.extension_lengths_mm = {0, 75, 150};  // equal gaps: the first
  CHECK(healthCheckExtension(bar) == 37.5);
  bar.extension_lengths_mm = {0};  // one extension: half the bar beyond it
  CHECK(healthCheckExtension(bar) == 75.0);
  bar.extension_lengths_mm = {100, 100};
  CHECK(healthCheckExtension(bar) == 175.0);
}

TEST_CASE("the check's connections use every ball and every chuck, from the cell's own") {
  CHECK(connectionList(healthCheckConnections(allConnections())) == "B1C2,B2C3,B3C1");
  CHECK(connectionList(healthCheckConnections(parseConnections("B1C1,B2C2,B3C3"))) ==
        "B1C1,B2C2,B3C3");
  // Without B1C2 the other rotation.
  std::vector<Connection> no_b1c2 = allConnections();
  no_b1c2.erase(no_b1c2.begin() + 1);
  CHECK(connectionList(healthCheckConnections(no_b1c2)) == "B1C3,B2C1,B3C2");
  // Six connections that use every ball and chuck always hold three that do.
  CHECK(connectionList(healthCheckConnections(parseConnections("B1C1,B1C2,B2C2,B2C3,B3C3,B3C1"))) ==
        "B1C2,B2C3,B3C1");
  CHECK_THROWS_AS(healthCheckConnections(parseConnections("B1C1,B1C2,B1C3")), PlanError);
  CHECK_THROWS_WITH(healthCheckConnections(parseConnections("B1C1,B2C1,B3C1")),
                    Catch::Contains("B1C1,B2C1,B3C1"));
}

TEST_CASE("the check cell keeps the calibration's bar, tool, margins and motion") {
  const CellConfig cell = healthCheckCell(gridCell());
  CHECK(connectionList(cell.connections) == "B1C2,B2C3");  // the first two of the three
  REQUIRE(cell.bar.extension_lengths_mm.size() == 1);
  CHECK(cell.bar.extension_lengths_mm[0] == 75.0);
  // The candidates' grid: 8 latitudes, 18 longitudes.
  CHECK(gridLatitudes(cell.grid).size() * gridLongitudes(cell.grid).size() == 144);
  CHECK(cell.bar.nominal_length_mm == gridCell().bar.nominal_length_mm);
  CHECK(cell.motion.settle_s == gridCell().motion.settle_s);
  CHECK(cell.margins.table_clearance_mm == gridCell().margins.table_clearance_mm);
  CHECK(cell.tool.min_bar_tool_angle_deg == gridCell().tool.min_bar_tool_angle_deg);
  CHECK_NOTHROW(validateCell(cell));
}

TEST_CASE("the check plan: 30 points on two shells at 75 mm, about 5 minutes in all") {
  const Plan& plan = checkPlanOfDefaultCell();
  CHECK(plan.purpose == PlanPurpose::kCheck);
  REQUIRE(plan.shells.size() == kHealthCheckShells);
  CHECK(connectionsOf(plan) == "B1C2,B2C3");
  for (const ShellPlan& s : plan.shells) {
    INFO("shell " << s.shell);
    CHECK(s.extension_mm == 75.0);
    CHECK(s.radius_mm == 225.0);
    CHECK(s.summary.points == kHealthCheckPoints / kHealthCheckShells);
    CHECK(s.dropped.empty());
  }
  // The planner's own estimate, with a minute of the operator's per shell.
  const double minutes = plan.summary.duration_s / 60;
  CHECK(minutes + kHealthCheckShells * kHealthCheckOperatorMinPerShell <= kHealthCheckMinutes);
}

TEST_CASE("the check's signatures taken point by point are the verdict's whitened test") {
  // S_k = d_k^2 e_k^T J^T (I + J C J^T)^-1 J e_k (noise 1) for random gradients J and a random
  // covariance C with a zero block (parameters the calibration fixes), against the sequence.
  std::mt19937_64 rng(3);
  std::normal_distribution<double> unit(0, 1);
  const int n = 12;
  Eigen::MatrixXd jac(n, kParamCount);
  for (Eigen::Index i = 0; i < jac.size(); ++i) jac(i) = unit(rng);
  Eigen::MatrixXd root(kParamCount, kParamCount);
  for (Eigen::Index i = 0; i < root.size(); ++i) root(i) = 0.3 * unit(rng);
  Eigen::MatrixXd covariance = root * root.transpose();
  covariance.topRows(6).setZero();
  covariance.leftCols(6).setZero();
  ParamVector targets;
  for (int k = 0; k < kParamCount; ++k) targets[k] = k % 5 == 0 ? 0.0 : 0.5 + 0.1 * (k % 7);
  for (const bool whitened : {false, true}) {
    INFO((whitened ? "whitened" : "white"));
    const Eigen::MatrixXd c =
        whitened ? covariance : Eigen::MatrixXd::Zero(kParamCount, kParamCount);
    CheckSignatures sequence(targets, c);
    for (int i = 0; i < n; ++i) {
      // What a point would add is what adding it adds.
      const Eigen::ArrayXd before = sequence.noncentrality();
      const Eigen::ArrayXXd gain = sequence.gains(jac.row(i));
      sequence.add(jac.row(i));
      for (int k = 0; k < kParamCount; ++k)
        CHECK(sequence.noncentrality()[k] - before[k] ==
              Approx(gain(0, k)).margin(1e-12 * sequence.noncentrality()[k]));
    }
    const Eigen::MatrixXd scatter = Eigen::MatrixXd::Identity(n, n) + jac * c * jac.transpose();
    const Eigen::MatrixXd whitened_jac = scatter.llt().matrixL().solve(jac);
    double least = 1e300;
    for (int k = 0; k < kParamCount; ++k) {
      const double batch = targets[k] * targets[k] * whitened_jac.col(k).squaredNorm();
      CHECK(sequence.noncentrality()[k] == Approx(batch).epsilon(1e-9));
      if (targets[k] > 0) least = std::min(least, batch);
    }
    CHECK(sequence.weakest() == Approx(least).epsilon(1e-9));
  }
}

TEST_CASE("the check's points are where the changes it must see stand out most") {
  // Against the same number of points of the old coarse grid (latitudes 30 and 70, longitudes
  // every 30 deg) on the same shells, judged as the design judges them (the verdict's whitened
  // test against the calibration the cell's grid would give): the weakest signature is stronger.
  const Plan& designed = checkPlanOfDefaultCell();
  CellConfig grid_cell = healthCheckCell(gridCell());
  grid_cell.grid = {30, 70, 40, 0, 60};  // 2 x 6 = 12 a shell
  const Plan grid = planCell(nominal(), grid_cell);
  auto weakest = [](const Plan& plan) {
    const Kinematics kin(nominal());
    CheckSignatures signatures = healthCheckSignatures(nominal(), gridCell());
    ParamRow g;
    for (const Sample& x : planSamples(nominal(), plan)) {
      kin.barLengthGradient(x.joints_deg, nominal().balls_mm[x.ball_index],
                            nominal().chucks_mm[x.chuck_index], g);
      signatures.add(g);
    }
    return signatures.weakest() / plan.summary.points;
  };
  CHECK(weakest(designed) > 1.2 * weakest(grid));
}

TEST_CASE("check-plan accepts the check plan against the calibration's cell and its own") {
  const Plan& plan = checkPlanOfDefaultCell();
  for (const auto& v : checkPlan(nominal(), gridCell(), plan)) FAIL(describeViolation(v));
  for (const auto& v : checkPlan(nominal(), healthCheckCell(gridCell()), plan))
    FAIL(describeViolation(v));
  // A calibration plan may not use the check's extension: only the purpose allows it.
  Plan as_calibration = plan;
  as_calibration.purpose = PlanPurpose::kCalibration;
  const auto v = checkPlan(nominal(), gridCell(), as_calibration);
  REQUIRE(v.size() == kHealthCheckShells);
  CHECK(v[0].rule == "extension");
  // Nor may a check plan use any other extension.
  Plan other = plan;
  other.shells[1].extension_mm = 50;
  other.shells[1].radius_mm = 200;
  const auto w = checkPlan(nominal(), gridCell(), other);
  REQUIRE_FALSE(w.empty());
  CHECK(w[0].rule == "extension");
  CHECK_THAT(w[0].message, Catch::Contains("nor its check extension"));
}

TEST_CASE("the plan file says what the plan is for, and old files are calibration plans") {
  const Plan back = parsePlan(formatPlan(checkPlanOfDefaultCell()), "check.json");
  CHECK(back.purpose == PlanPurpose::kCheck);
  CHECK(back.summary.points == checkPlanOfDefaultCell().summary.points);
  CHECK(checkPlan(nominal(), gridCell(), back).empty());

  nlohmann::json j = nlohmann::json::parse(formatPlan(checkPlanOfDefaultCell()));
  CHECK(j["purpose"] == "check");
  j.erase("purpose");
  CHECK(parsePlan(j.dump(), "old.json").purpose == PlanPurpose::kCalibration);
  j["purpose"] = "calibration";
  CHECK(parsePlan(j.dump(), "plan.json").purpose == PlanPurpose::kCalibration);
  j["purpose"] = "verification";
  CHECK_THAT(planErrorOf(j.dump()), Catch::Contains("purpose") && Catch::Contains("\"check\""));
  j["purpose"] = 2;
  CHECK_THAT(planErrorOf(j.dump()), Catch::Contains("purpose"));
  CHECK(std::string(planPurposeName(PlanPurpose::kCheck)) == "check");
  CHECK(parsePlanPurpose("calibration") == PlanPurpose::kCalibration);
  CHECK_FALSE(parsePlanPurpose("Check").has_value());
}

TEST_CASE("the check plan's own points: an unchanged robot passes, a moved joint 2 fails") {
  // A calibrated model of a perturbed truth (the reference cell's grid plan, at the paper's
  // noise), then the check plan's points measured on that truth and on the truth with joint 2's
  // offset moved.
  const Model& nom = nominal();
  const Plan& plan = checkPlanOfDefaultCell();
  std::mt19937_64 rng(5);
  const Model truth = perturbModel(nom, PerturbationSigmas{}, rng);
  std::vector<Sample> calibration = planSamples(truth, planCell(nom, gridCell()));
  std::normal_distribution<double> calibration_noise(0, 0.084);
  for (Sample& s : calibration) s.length_mm += calibration_noise(rng);
  const SolveResult fit = solveCalibration(nom, calibration);
  Model active = withParams(nom, fit.params);
  active.provenance = ModelProvenance{};
  active.provenance->rms_mm = fit.after.rms_mm;
  active.covariance = fit.covariance;  // as a written model carries it

  auto checkSamples = [&](const Model& robot) {
    std::normal_distribution<double> noise(0, 0.084);
    std::vector<Sample> out = planSamples(robot, plan);
    for (Sample& s : out) s.length_mm += noise(rng);
    return out;
  };
  const HealthVerdict same = assessHealth(active, checkSamples(truth));
  CHECK(same.samples == static_cast<size_t>(plan.summary.points));
  CHECK(same.status == HealthStatus::kPass);
  CHECK(same.moved.empty());
  Model moved = truth;
  moved.joints[1].offset_deg += 0.05;
  const HealthVerdict changed = assessHealth(active, checkSamples(moved));
  CHECK(changed.status == HealthStatus::kFail);
  REQUIRE_FALSE(changed.moved.empty());
  CHECK(changed.moved[0].name == "J2.offset");
  CHECK(changed.moved[0].change == Approx(0.05).margin(0.01));
}

TEST_CASE("robocal plan --check writes the check plan and check-plan accepts it", "[cli]") {
  const std::string path = tempPath("check.json");
  std::string out;
  const std::string args =
      " --model " + kSource + "/config/puma560-paper.json --cell " + kSource + "/config/cell.json ";
  const int status =
      runCommand(robocalBinary() + " plan --check --quiet" + args + "--out " + path, out);
  INFO(out);
  REQUIRE(status == 0);
  CHECK_THAT(out, Catch::Contains("check plan: ") && Catch::Contains("points on 2 shells") &&
                      Catch::Contains("B1C2,B2C3)") && Catch::Contains("extension 75 mm") &&
                      Catch::Contains("min of robot time"));
  const Plan plan = loadPlanFile(path);
  CHECK(plan.purpose == PlanPurpose::kCheck);
  CHECK(plan.shells.size() == 2);
  CHECK(runCommand(robocalBinary() + " check-plan" + args + path, out) == 0);
  CHECK_THAT(out, Catch::Contains("OK"));
  CHECK_THAT(out, !Catch::Contains("other settings"));
  std::remove(path.c_str());
}
