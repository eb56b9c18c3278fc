#include <catch2/catch.hpp>

#include "fixtures.hpp"

#include <robocal/formats/model_json.hpp>
#include <robocal/formats/samples_csv.hpp>
#include <robocal/planner/cell_json.hpp>
#include <robocal/planner/check.hpp>
#include <robocal/planner/plan.hpp>
#include <robocal/planner/plan_json.hpp>
#include <robocal/robot/puma560.hpp>
#include <robocal/robot/puma_ik.hpp>
#include <robocal/sim/measurements.hpp>

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
using test::shippedCell;

// The grid cell's plan, made once for all the tests that read it.
const Plan& gridPlan() {
  static const Plan p = planCell(nominal(), gridCell());
  return p;
}

// Largest |ball-chuck distance - radius| along the joint-interpolated move a -> b, sampled
// independently of the planner: at least every 0.25 mm of ball travel.
double worstDeviation(const Kinematics& kin, const Model& m, const ShellPlan& shell,
                      const JointsDeg& a, const JointsDeg& b) {
  const Eigen::Vector3d ball = m.balls_mm[shell.connection.ball_index];
  const Eigen::Vector3d chuck = m.chucks_mm[shell.connection.chuck_index];
  int n = 16;
  for (;;) {
    double worst = 0, gap = 0;
    Eigen::Vector3d prev = kin.ballPosition(a, ball);
    for (int i = 0; i <= n; ++i) {
      const JointsDeg q = a + (b - a) * (double(i) / n);
      const Eigen::Vector3d p = kin.ballPosition(q, ball);
      gap = std::max(gap, (p - prev).norm());
      prev = p;
      worst = std::max(worst, std::abs((p - chuck).norm() - shell.radius_mm));
    }
    if (gap <= 0.25) return worst;
    n *= 2;
  }
}

std::string robocalBinary() {
  if (const char* dir = std::getenv("ROBOCAL_BIN")) return std::string(dir) + "/robocal";
  return std::string(ROBOCAL_BINARY_DIR) + "/cli/robocal";
}

// A file name of this process (ctest runs test cases in parallel processes).
std::string tempPath(const std::string& name) {
  return std::string(ROBOCAL_BINARY_DIR) + "/test_planner_" + std::to_string(::getpid()) + "_" +
         name;
}

// Removes the listed files when it goes out of scope.
struct TempFiles {
  std::vector<std::string> paths;
  ~TempFiles() {
    for (const std::string& p : paths) std::remove(p.c_str());
  }
};

int runCommand(const std::string& command, std::string& output) {
  const std::string out_path = tempPath("cmd_output.txt");
  const TempFiles cleanup{{out_path}};
  const int status = std::system((command + " > " + out_path + " 2>&1").c_str());
  std::ifstream in(out_path);
  std::stringstream text;
  text << in.rdbuf();
  output = text.str();
  return status;
}

}  // namespace

TEST_CASE("the default cell plans nine shells per extension, each with at least 80 points") {
  const Plan& plan = gridPlan();
  REQUIRE(plan.shells.size() == 18);
  for (const ShellPlan& s : plan.shells) {
    INFO("shell " << s.shell << " " << connectionName(s.connection));
    CHECK(s.summary.points >= 80);
    CHECK(s.radius_mm == Approx(gridCell().bar.nominal_length_mm + s.extension_mm));
    CHECK(s.summary.max_deviation_mm <= gridCell().motion.via_tolerance_mm);
    CHECK(s.summary.duration_s > s.summary.points * gridCell().motion.settle_s);
    // Every grid point is either planned or listed as dropped, with a reason.
    CHECK(s.summary.points + static_cast<int>(s.dropped.size()) == 8 * 12);
    for (const DroppedPoint& d : s.dropped) CHECK_FALSE(d.reason.empty());
  }
  int first_set = 0, second_set = 0;
  for (const ShellPlan& s : plan.shells) (s.extension_mm == 0 ? first_set : second_set)++;
  CHECK(first_set == 9);
  CHECK(second_set == 9);
}

TEST_CASE("the default plan identifies all 36 independent parameters") {
  const PlanIdentifiability all = planIdentifiability(nominal(), gridPlan());
  CHECK(all.rank == 36);
  CHECK(all.condition_number > 1);
  CHECK(all.condition_number < 1e4);
  for (double e : {0.0, 150.0}) {
    INFO("extension " << e);
    CHECK(planIdentifiability(nominal(), gridPlan(), e).rank == 36);
  }
}

TEST_CASE("every move of the plan keeps the nominal radial deviation within via_tolerance",
          "[heavy]") {
  const Kinematics kin(nominal());
  const double tol = gridCell().motion.via_tolerance_mm;
  double worst = 0;
  long segments = 0;
  for (const ShellPlan& s : gridPlan().shells) {
    JointsDeg prev = s.connect.joints_deg;
    for (size_t i = 0; i < s.steps.size(); ++i) {
      const double d = worstDeviation(kin, nominal(), s, prev, s.steps[i].joints_deg);
      if (d > tol) FAIL("shell " << s.shell << " step " << i << ": deviation " << d << " mm");
      worst = std::max(worst, d);
      prev = s.steps[i].joints_deg;
      ++segments;
    }
  }
  CHECK(segments > 1000);
  CHECK(worst <= tol);
  CHECK(worst > 0.1 * tol);  // the vias are not wastefully dense either
}

TEST_CASE(
    "every pose of the plan is inside the limits minus the margin, away from "
    "singularities, in its shell's configuration") {
  const CellConfig& cell = gridCell();
  const PumaIk ik(nominal());
  for (const ShellPlan& s : gridPlan().shells) {
    std::vector<const PlanStep*> poses = {&s.connect};
    for (const PlanStep& st : s.steps) poses.push_back(&st);
    for (size_t i = 0; i < poses.size(); ++i) {
      const JointsDeg& q = poses[i]->joints_deg;
      INFO("shell " << s.shell << " pose " << i);
      CHECK(withinLimits(nominal(), q, cell.margins.joint_limit_deg));
      const SingularityMargins m = ik.singularityMargins(q);
      CHECK(m.wrist_deg >= cell.margins.wrist_singularity_deg);
      CHECK(m.elbow_deg >= cell.margins.elbow_singularity_deg);
      CHECK(m.shoulder_mm >= cell.margins.shoulder_singularity_mm);
      CHECK(ik.configOf(q) == s.config);
    }
  }
}

TEST_CASE("check-plan accepts the plan, also after a round trip through the file format",
          "[heavy]") {
  const Plan& plan = gridPlan();
  CHECK(checkPlan(nominal(), gridCell(), plan).empty());
  const Plan back = parsePlan(formatPlan(plan), "round trip");
  REQUIRE(back.shells.size() == plan.shells.size());
  for (size_t i = 0; i < plan.shells.size(); ++i) {
    REQUIRE(back.shells[i].steps.size() == plan.shells[i].steps.size());
    CHECK(back.shells[i].connection == plan.shells[i].connection);
    CHECK(back.shells[i].config == plan.shells[i].config);
    CHECK(back.shells[i].dropped.size() == plan.shells[i].dropped.size());
  }
  CHECK(back.summary.points == plan.summary.points);
  const auto violations = checkPlan(nominal(), gridCell(), back);
  for (const auto& v : violations) UNSCOPED_INFO(describeViolation(v));
  CHECK(violations.empty());
}

TEST_CASE("check-plan catches a hand-corrupted plan and names the step", "[heavy]") {
  Plan plan = gridPlan();
  ShellPlan& shell = plan.shells[2];
  SECTION("a joint nudged by 2 degrees") {
    size_t index = 10;
    shell.steps[index].joints_deg[1] += 2.0;
    const auto v = checkPlan(nominal(), gridCell(), plan);
    REQUIRE_FALSE(v.empty());
    CHECK(v[0].shell == shell.shell);
    CHECK(v[0].step == static_cast<int>(index));
  }
  SECTION("a via removed: the move leaves the tolerance") {
    size_t via = 0;
    while (shell.steps[via].kind != StepKind::kVia) ++via;
    shell.steps.erase(shell.steps.begin() + static_cast<long>(via));
    const auto v = checkPlan(nominal(), gridCell(), plan);
    REQUIRE(v.size() == 1);
    CHECK(v[0].rule == "deviation");
    CHECK(v[0].step == static_cast<int>(via));  // the move that now ends at the old next step
  }
  SECTION("a joint past its limit") {
    shell.steps[5].joints_deg[4] = 99.0;  // J5 limit is 100, margin 5
    const auto v = checkPlan(nominal(), gridCell(), plan);
    REQUIRE_FALSE(v.empty());
    bool found = false;
    for (const auto& x : v) found |= x.step == 5 && x.rule == "limits";
    CHECK(found);
  }
  SECTION("a configuration flipped") {
    shell.config.wrist_flip = !shell.config.wrist_flip;
    const auto v = checkPlan(nominal(), gridCell(), plan);
    CHECK(v.size() == shell.steps.size() + 1);  // every pose of that shell
    CHECK(v[0].rule == "configuration");
  }
  SECTION("a wrong extension") {
    shell.extension_mm = 50;
    const auto v = checkPlan(nominal(), gridCell(), plan);
    REQUIRE_FALSE(v.empty());
    CHECK(v[0].rule == "extension");
  }
}

TEST_CASE("robocal check-plan prints each violation with its step and exits non-zero",
          "[cli][heavy]") {
  nlohmann::json j = nlohmann::json::parse(formatPlan(gridPlan()));
  const std::string good = tempPath("good_plan.json");
  const std::string bad = tempPath("bad_plan.json");
  const TempFiles cleanup{{good, bad}};
  std::ofstream(good) << j.dump();
  j["shells"][4]["steps"][7]["joints_deg"][2] =
      j["shells"][4]["steps"][7]["joints_deg"][2].get<double>() + 3.0;
  std::ofstream(bad) << j.dump();
  const std::string base = robocalBinary() + " check-plan --model " + kSource +
                           "/config/puma560-paper.json --cell " + kSource + "/config/cell.json ";
  std::string out;
  CHECK(runCommand(base + good, out) == 0);
  CHECK(out.find("OK") != std::string::npos);
  CHECK(runCommand(base + bad, out) != 0);
  INFO(out);
  CHECK(out.find("shell 5 step 7") != std::string::npos);
}

TEST_CASE("singularity margins reject poses near a singularity") {
  const ShellPlanner planner(nominal(), gridCell());
  const Connection c{0, 0};
  // A planned pose, then the same with joint 5 turned close to zero.
  const PlanStep& step = gridPlan().shells[0].steps[0];
  CHECK(planner.poseProblem(c, gridPlan().shells[0].radius_mm, step.joints_deg, 0.5).empty());
  JointsDeg q = step.joints_deg;
  q[4] = 3.0;
  const std::string problem = planner.poseProblem(c, gridPlan().shells[0].radius_mm, q, 1e9);
  CHECK(problem.find("wrist") != std::string::npos);

  // A shoulder margin no pose can keep (the arm reaches less than 2 m): every point of the
  // shell is dropped with that reason, and planning the cell fails with a clear error.
  CellConfig cell = gridCell();
  cell.connections = {Connection{0, 0}};
  cell.bar.extension_lengths_mm = {0};
  cell.margins.shoulder_singularity_mm = 2000;
  const ShellPlan shell = ShellPlanner(nominal(), cell).planShell(c, 0, 1);
  CHECK(shell.summary.points == 0);
  REQUIRE(shell.dropped.size() == 96);
  for (const DroppedPoint& d : shell.dropped)
    CHECK(d.reason.find("shoulder singularity") != std::string::npos);
  CHECK_THROWS_AS(planCell(nominal(), cell), PlanError);
  cell.margins.shoulder_singularity_mm = gridCell().margins.shoulder_singularity_mm;

  // A moderate margin: fewer points, but every planned pose keeps it.
  cell.margins.wrist_singularity_deg = 30;
  const Plan p = planCell(nominal(), cell);
  const PumaIk ik(nominal());
  for (const PlanStep& s : p.shells[0].steps)
    CHECK(ik.singularityMargins(s.joints_deg).wrist_deg >= 30);
}

TEST_CASE(
    "unreachable grids: out-of-reach shells are refused, partly reachable ones list the "
    "dropped points") {
  CellConfig cell = gridCell();
  cell.connections = {Connection{1, 2}};
  SECTION("a radius far beyond the arm's reach") {
    cell.bar.extension_lengths_mm = {3000};
    try {
      planCell(nominal(), cell);
      FAIL("planned an unreachable shell");
    } catch (const PlanError& e) {
      CHECK(std::string(e.what()).find("no grid point") != std::string::npos);
    }
  }
  SECTION("a large shell: some points out of reach") {
    cell.bar.extension_lengths_mm = {400};
    const Plan p = planCell(nominal(), cell);
    const ShellPlan& s = p.shells[0];
    CHECK(s.summary.points > 0);
    CHECK_FALSE(s.dropped.empty());
    CHECK(s.summary.points + static_cast<int>(s.dropped.size()) == 96);
    CHECK(checkPlan(nominal(), cell, p).empty());
  }
  SECTION("impossible margins name the key") {
    cell.margins.joint_limit_deg = 200;
    try {
      planCell(nominal(), cell);
      FAIL("accepted a joint-limit margin larger than the joints' ranges");
    } catch (const PlanError& e) {
      CHECK(std::string(e.what()).find("margins.joint_limit_deg") != std::string::npos);
    }
  }
  SECTION("bad settings name the key") {
    cell.motion.via_tolerance_mm = 3.0;  // more than the bar's range
    try {
      ShellPlanner planner(nominal(), cell);
      FAIL("accepted a tolerance beyond the bar's range");
    } catch (const PlanError& e) {
      CHECK(std::string(e.what()).find("motion.via_tolerance_mm") != std::string::npos);
    }
  }
}

TEST_CASE("a fixed arm configuration is kept on every shell") {
  CellConfig cell = gridCell();
  cell.arm_configuration = "right-up-noflip";
  cell.bar.extension_lengths_mm = {0};
  cell.connections = {Connection{0, 0}, Connection{2, 2}};
  const Plan p = planCell(nominal(), cell);
  const PumaIk ik(nominal());
  for (const ShellPlan& s : p.shells) {
    CHECK(armConfigName(s.config) == "right-up-noflip");
    for (const PlanStep& st : s.steps)
      CHECK(armConfigName(ik.configOf(st.joints_deg)) == "right-up-noflip");
  }
  CHECK(checkPlan(nominal(), cell, p).empty());
}

TEST_CASE("re-planning the rest of a shell with a refined model keeps it safe for that model") {
  std::mt19937_64 rng(3);
  const Model truth = perturbModel(nominal(), PerturbationSigmas{}, rng);
  const ShellPlan& old = gridPlan().shells[4];
  const ShellPlanner planner(truth, gridCell());
  const size_t next = old.steps.size() / 2;
  const JointsDeg here = old.steps[next - 1].joints_deg;
  const ShellPlan fresh = planner.replanRemaining(old, next, here);
  // The kept part is unchanged; the rest has (about) the same points.
  for (size_t i = 0; i < next; ++i) CHECK(fresh.steps[i].joints_deg == old.steps[i].joints_deg);
  int old_points = 0, new_points = 0;
  for (size_t i = next; i < old.steps.size(); ++i)
    old_points += old.steps[i].kind == StepKind::kPoint;
  for (size_t i = next; i < fresh.steps.size(); ++i)
    new_points += fresh.steps[i].kind == StepKind::kPoint;
  CHECK(new_points + static_cast<int>(fresh.dropped.size() - old.dropped.size()) == old_points);
  CHECK(new_points >= old_points - 2);

  // From the very start too: the connect pose is off the refined model's shell by the model
  // difference, and the first move is allowed that much.
  const ShellPlan whole = planner.replanRemaining(old, 0, old.connect.joints_deg);
  CHECK(whole.summary.points >= old.summary.points - 2);

  // The new steps keep every rule for the refined model. (The robot's current pose was planned
  // for the old model, so the check starts at the first re-planned step.)
  Plan rest;
  rest.cell = gridCell();
  ShellPlan part = fresh;
  part.connect = fresh.steps[next];
  part.steps.assign(fresh.steps.begin() + static_cast<long>(next) + 1, fresh.steps.end());
  rest.shells.push_back(part);
  const auto v = checkPlan(truth, gridCell(), rest);
  for (const auto& x : v) UNSCOPED_INFO(describeViolation(x));
  CHECK(v.empty());
  // And the points are on the refined model's shell.
  const Kinematics kin(truth);
  for (const PlanStep& s : part.steps)
    if (s.kind == StepKind::kPoint)
      CHECK(std::abs(kin.barLength(s.joints_deg, truth.balls_mm[old.connection.ball_index],
                                   truth.chucks_mm[old.connection.chuck_index]) -
                     old.radius_mm) < 1e-6);
}

namespace {

// Points whose last move into them is not upward in every joint (motion.approach_deg).
int pointsNotApproachedFromBelow(const ShellPlan& shell, size_t from = 0) {
  int bad = 0;
  for (size_t i = std::max<size_t>(from, 1); i < shell.steps.size(); ++i) {
    if (shell.steps[i].kind != StepKind::kPoint) continue;
    const JointsDeg step = shell.steps[i].joints_deg - shell.steps[i - 1].joints_deg;
    bad += shell.steps[i - 1].kind != StepKind::kVia || step.minCoeff() < 0.02 - 1e-9;
  }
  return bad;
}

}  // namespace

TEST_CASE(
    "the shipped cell's plan reaches every point from below in every joint (approach_deg), "
    "revisits a few, and check-plan accepts it") {
  const CellConfig& cell = shippedCell();
  CHECK(cell.motion.approach_deg == 0.02);
  CHECK(cell.motion.revisit_every > 0);
  const Plan plan = planCell(nominal(), cell);
  int revisits = 0;
  for (const ShellPlan& shell : plan.shells)
    for (const PlanStep& step : shell.steps)
      revisits += step.kind == StepKind::kPoint && step.visit;
  CHECK(revisits > plan.summary.points / cell.motion.revisit_every / 2);
  int points = 0;
  for (const ShellPlan& shell : plan.shells) {
    INFO("shell " << shell.shell);
    CHECK(pointsNotApproachedFromBelow(shell) == 0);
    points += shell.summary.points;
  }
  CHECK(points > 1650);  // the pre-points cost a few points near the poles, not more
  CHECK(checkPlan(nominal(), cell, plan).empty());
  // A re-planned rest of a shell keeps the rule.
  std::mt19937_64 rng(4);
  const Model truth = perturbModel(nominal(), PerturbationSigmas{}, rng);
  const ShellPlan& old = plan.shells[2];
  const size_t next = old.steps.size() / 3;
  const ShellPlan fresh =
      ShellPlanner(truth, cell).replanRemaining(old, next, old.steps[next - 1].joints_deg);
  CHECK(pointsNotApproachedFromBelow(fresh, next + 1) == 0);
  // Without it (the default), many points are reached from above in some joint.
  const ShellPlan& plain = gridPlan().shells[2];
  CHECK(pointsNotApproachedFromBelow(plain) > plain.summary.points / 4);
}

namespace {

// A plan of `shell` alone: check-plan accepts it, and its steps' visit counts survive the file.
Plan checkedAndKeptInFile(const CellConfig& cell, const ShellPlan& shell) {
  Plan plan;
  plan.cell = cell;
  plan.shells = {shell};
  CHECK(checkPlan(nominal(), cell, plan).empty());
  const Plan back = parsePlan(formatPlan(plan), "p.json");
  REQUIRE(back.shells[0].steps.size() == shell.steps.size());
  for (size_t i = 0; i < shell.steps.size(); ++i)
    CHECK(back.shells[0].steps[i].visit == shell.steps[i].visit);
  return plan;
}

}  // namespace

TEST_CASE("with revisit_every a few points are measured again, reached the same way, and kept") {
  CellConfig cell = gridCell();
  cell.motion.approach_deg = 0.02;
  cell.motion.revisit_every = 20;
  const ShellPlan shell = ShellPlanner(nominal(), cell).planShell({0, 0}, 0, 1);
  int firsts = 0, revisits = 0;
  for (size_t i = 0; i < shell.steps.size(); ++i) {
    const PlanStep& step = shell.steps[i];
    if (step.kind != StepKind::kPoint) continue;
    if (step.visit == 0) {
      ++firsts;
      continue;
    }
    ++revisits;
    // The same place and joints as an earlier first visit, measured after another point.
    const auto first = std::find_if(shell.steps.begin(), shell.steps.begin() + i, [&](auto& s) {
      return s.kind == StepKind::kPoint && s.visit == 0 && s.lat_deg == step.lat_deg &&
             s.lon_deg == step.lon_deg;
    });
    REQUIRE(first != shell.steps.begin() + i);
    CHECK((first->joints_deg - step.joints_deg).cwiseAbs().maxCoeff() < 1e-9);
    CHECK(std::any_of(first + 1, shell.steps.begin() + i, [](const PlanStep& s) {
      return s.kind == StepKind::kPoint;  // the arm measured elsewhere in between
    }));
  }
  CHECK(revisits == firsts / 20);
  CHECK(pointsNotApproachedFromBelow(shell) == 0);  // the revisits too
  // The visit survives the file and a re-plan of the rest; a plan file's bad visit is refused.
  const Plan plan = checkedAndKeptInFile(cell, shell);
  const ShellPlan rest =
      ShellPlanner(nominal(), cell).replanRemaining(shell, 1, shell.connect.joints_deg);
  int replanned_revisits = 0;
  for (const PlanStep& step : rest.steps) replanned_revisits += step.visit;
  CHECK(replanned_revisits == revisits);
  std::string text = formatPlan(plan);
  const auto at = text.find("\"lat_deg\"", text.find("\"steps\""));
  text.insert(at, "\"visit\": 10001, ");
  CHECK_THROWS_WITH(parsePlan(text, "p.json"), Catch::Contains("visit"));
}

TEST_CASE("with reference_every_min the shell's first point is measured again every few minutes") {
  CellConfig cell = gridCell();
  cell.motion.approach_deg = 0.02;
  cell.motion.reference_every_min = 2;
  const ShellPlanner planner(nominal(), cell);
  const ShellPlan shell = planner.planShell({0, 0}, 0, 1);
  const auto first_point = std::find_if(shell.steps.begin(), shell.steps.end(),
                                        [](auto& s) { return s.kind == StepKind::kPoint; });
  REQUIRE(first_point != shell.steps.end());
  auto isReference = [&](const PlanStep& s) {
    return s.kind == StepKind::kPoint && s.lat_deg == first_point->lat_deg &&
           s.lon_deg == first_point->lon_deg;
  };
  // The planned robot time from each measurement of the reference to the next.
  std::vector<double> gaps_s;
  double since_s = 0, longest_point_s = 0, point_s = 0;
  int expected_visit = 0;
  for (size_t i = 0; i < shell.steps.size(); ++i) {
    const PlanStep& step = shell.steps[i];
    const JointsDeg& from = i == 0 ? shell.connect.joints_deg : shell.steps[i - 1].joints_deg;
    const double move_s =
        (step.joints_deg - from).cwiseAbs().maxCoeff() / cell.motion.joint_speed_deg_per_s +
        cell.motion.move_overhead_s;
    since_s += move_s;
    point_s += move_s;
    if (step.kind != StepKind::kPoint) continue;
    since_s += cell.motion.settle_s;
    point_s += cell.motion.settle_s;
    longest_point_s = std::max(longest_point_s, point_s);
    point_s = 0;
    if (!isReference(step)) continue;
    CHECK(step.visit == expected_visit++);  // 0, 1, 2, ...: each measurement counted
    CHECK((step.joints_deg - first_point->joints_deg).cwiseAbs().maxCoeff() < 1e-9);
    if (step.visit > 0) gaps_s.push_back(since_s);
    since_s = 0;
  }
  const double shell_min = shell.summary.duration_s / 60;
  INFO("shell of " << shell_min << " min, " << gaps_s.size() << " repeats");
  REQUIRE(gaps_s.size() >= static_cast<size_t>(shell_min / 2) - 1);
  // Every 2 minutes, give or take the point that crosses it; the last one closes the shell.
  for (size_t g = 0; g + 1 < gaps_s.size(); ++g) {
    CHECK(gaps_s[g] >= 120 - 1e-9);
    CHECK(gaps_s[g] <= 120 + 2 * longest_point_s);
  }
  CHECK(isReference(shell.steps.back()));
  CHECK(pointsNotApproachedFromBelow(shell) == 0);
  // The counts survive the plan file and a re-plan of the rest (a resume).
  checkedAndKeptInFile(cell, shell);
  CHECK(parseCell(cellToJson(cell).dump(), "c.json").motion.reference_every_min == 2);
  const ShellPlan rest = planner.replanRemaining(shell, 1, shell.connect.joints_deg);
  CHECK(std::count_if(rest.steps.begin(), rest.steps.end(), isReference) == expected_visit);
}

TEST_CASE("the deflection forecast grows with the model uncertainty") {
  Plan plan = gridPlan();
  std::mt19937_64 rng(5);
  PerturbationSigmas small;
  small.translation_mm = 0.02;
  small.link_angle_deg = 0.002;
  small.joint_offset_deg = 0.005;
  small.gain = 0.00005;
  std::vector<Model> few, many;
  for (int i = 0; i < 5; ++i) few.push_back(perturbModel(nominal(), small, rng));
  for (int i = 0; i < 5; ++i) many.push_back(perturbModel(nominal(), PerturbationSigmas{}, rng));
  predictDeflections(nominal(), {}, plan);
  CHECK(plan.summary.predicted_deflection_mm < 0);
  predictDeflections(nominal(), {nominal()}, plan);  // a perfect model: only the vias' deviation
  CHECK(plan.summary.predicted_deflection_mm == Approx(plan.summary.max_deviation_mm));
  predictDeflections(nominal(), few, plan);
  const double low = plan.summary.predicted_deflection_mm;
  predictDeflections(nominal(), many, plan);
  const double high = plan.summary.predicted_deflection_mm;
  CHECK(low > plan.summary.max_deviation_mm);
  CHECK(high > low);
  for (const ShellPlan& s : plan.shells) CHECK(s.summary.predicted_deflection_mm > 0);
}

TEST_CASE("robocal simulate --plan samples at the plan's data points", "[cli]") {
  CellConfig cell = gridCell();
  cell.connections = {Connection{0, 1}, Connection{2, 0}};
  cell.bar.extension_lengths_mm = {0};
  const Plan plan = planCell(nominal(), cell);
  const std::string plan_path = tempPath("sim_plan.json");
  const std::string csv_path = tempPath("sim_samples.csv");
  const TempFiles cleanup{{plan_path, csv_path}};
  savePlanFile(plan_path, plan);
  std::string out;
  const int status = runCommand(robocalBinary() + " simulate --model " + kSource +
                                    "/config/puma560-paper.json --plan " + plan_path + " --out " +
                                    csv_path + " --noise-mm 0",
                                out);
  INFO(out);
  REQUIRE(status == 0);
  const std::vector<Sample> samples = loadSamplesFile(csv_path);
  const std::vector<Sample> expected = planSamples(nominal(), plan);
  REQUIRE(samples.size() == expected.size());
  for (size_t i = 0; i < samples.size(); ++i) {
    CHECK(samples[i].shell == expected[i].shell);
    CHECK(samples[i].ball_index == expected[i].ball_index);
    CHECK(samples[i].chuck_index == expected[i].chuck_index);
    CHECK(samples[i].lat_deg == Approx(expected[i].lat_deg).margin(1e-3));
    CHECK((samples[i].joints_deg - expected[i].joints_deg).cwiseAbs().maxCoeff() < 1e-5);
    // The perturbed robot: near the shell, not on it.
    CHECK(std::abs(samples[i].length_mm - 150.0) < 10.0);
    // Each sample says how its point was reached: the plan's approach.
    REQUIRE(samples[i].approach_deg);
    CHECK(*samples[i].approach_deg == Approx(plan.cell.motion.approach_deg).margin(1e-4));
  }
  // Options that would contradict the plan are refused.
  CHECK(runCommand(robocalBinary() + " simulate --model " + kSource +
                       "/config/puma560-paper.json --plan " + plan_path + " --bar-mm 100",
                   out) != 0);
}

TEST_CASE("the flange and the wrist centre keep their distance from the bar") {
  const ShellPlan& shell = gridPlan().shells[0];
  const ShellPlanner planner(nominal(), gridCell());
  const PoseReport r =
      planner.inspect(shell.connection, shell.radius_mm, shell.steps[0].joints_deg);
  CHECK(r.bar_clearance_mm >= gridCell().margins.bar_clearance_mm);
  CellConfig cell = gridCell();
  cell.margins.bar_clearance_mm = r.bar_clearance_mm + 1.0;
  const ShellPlanner strict(nominal(), cell);
  const std::string problem =
      strict.poseProblem(shell.connection, shell.radius_mm, shell.steps[0].joints_deg, 0.5);
  CHECK(problem.find("from the bar") != std::string::npos);
  // check-plan reports it under its own rule.
  Plan plan;
  plan.shells.push_back(shell);
  bool found = false;
  for (const PlanViolation& v : checkPlan(nominal(), cell, plan))
    found |= v.step == 0 && v.rule == "bar clearance";
  CHECK(found);
}

namespace {

// A one-shell plan file with `shell`, the shell's `points` and its step's `lat_deg` as given.
std::string tinyPlan(const std::string& shell, const std::string& points,
                     const std::string& lat_deg) {
  return R"({"format": "robocal-plan", "version": 1, "settings": {}, "shells": [{"shell": )" +
         shell + R"(, "connection": "B1C1", "extension_mm": 0, "radius_mm": 150,
         "arm_configuration": "right-up-noflip", "summary": {"points": )" +
         points + R"(, "vias": 0},
         "connect": {"joints_deg": [0, -90, 90, 0, 45, 0], "lat_deg": 90, "lon_deg": 0},
         "steps": [{"kind": "point", "joints_deg": [0, -80, 90, 0, 45, 0], "lat_deg": )" +
         lat_deg + R"(, "lon_deg": 0}]}]})";
}

std::string planErrorOf(const std::string& text) {
  try {
    parsePlan(text, "plan.json");
  } catch (const FormatError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("hostile plan files are a FormatError and written plans read back (found by fuzz_plan)") {
  CHECK(planErrorOf(tinyPlan("1", "1", "10")).empty());
  // A number too large for a double escaped as json::out_of_range.
  CHECK_THAT(planErrorOf(tinyPlan("1", "1", "-212.4165311e30838")),
             Catch::Contains("plan.json: not valid JSON"));
  // Numbers too large for an int were converted anyway (undefined behaviour).
  CHECK_THAT(planErrorOf(tinyPlan("1e300", "1", "10")), Catch::Contains("shells[0].shell"));
  CHECK_THAT(planErrorOf(tinyPlan("1", "1e300", "10")),
             Catch::Contains("shells[0].summary.points"));
  CHECK_THAT(planErrorOf(tinyPlan("1", "-2", "10")), Catch::Contains("shells[0].summary.points"));
  // Deeply nested values were copied (the connect pose) or dumped (the version) recursively,
  // one level per call: 200000 levels overflowed the stack.
  const std::string deep = std::string(200000, '[') + std::string(200000, ']');
  std::string text = tinyPlan("1", "1", "10");
  const std::string connect =
      R"({"joints_deg": [0, -90, 90, 0, 45, 0], "lat_deg": 90, "lon_deg": 0})";
  REQUIRE(text.find(connect) != std::string::npos);
  text.replace(text.find(connect), connect.size(), deep);
  CHECK_THAT(planErrorOf(text), Catch::Contains("shells[0].connect: expected an object"));
  std::string version = tinyPlan("1", "1", "10");
  version.replace(version.find("\"version\": 1"), 12, "\"version\": " + deep);
  CHECK_THAT(planErrorOf(version), Catch::Contains("version: expected 1, got array"));
  // A huge but finite angle was written as null (rounding overflowed to infinity).
  const Plan plan = parsePlan(tinyPlan("1", "1", "1e300"), "plan.json");
  const Plan back = parsePlan(formatPlan(plan), "written");
  REQUIRE(back.shells.size() == 1);
  REQUIRE(back.shells[0].steps.size() == 1);
  CHECK(back.shells[0].steps[0].lat_deg == 1e300);
}
