// Optimal plans (planner/design.hpp): the objective agrees with the fit's own covariance, the
// optimiser beats a grid of as many points, keeps the budget and every safety rule, and its
// tours are short.
#include <catch2/catch.hpp>

#include "fixtures.hpp"

#include <robocal/compensation/accuracy.hpp>
#include <robocal/kinematics/kinematics.hpp>
#include <robocal/planner/cell_json.hpp>
#include <robocal/planner/check.hpp>
#include <robocal/planner/design.hpp>
#include <robocal/planner/plan_json.hpp>
#include <robocal/solver/calibrate.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

using namespace robocal;
using test::gridCell;
using test::nominal;

namespace {

// Three connections that use every ball and chuck, one extension: plans in about a second.
CellConfig smallCell() {
  CellConfig cell = gridCell();
  cell.connections = parseConnections("B1C2,B2C3,B3C1");
  cell.bar.extension_lengths_mm = {0, 150};
  cell.grid.latitude_step_deg = 20;
  cell.grid.longitude_step_deg = 60;
  return cell;
}

DesignOptions smallOptions() {
  DesignOptions o;
  o.candidate_grid = {10, 80, 10, 0, 30};
  o.orientations = 2;
  return o;
}

const std::vector<JointsDeg>& workJoints() {
  static const std::vector<JointsDeg> joints = [] {
    WorkVolume work = gridCell().work_volume;
    work.poses = 60;
    return workVolumeJoints(work, Compensator(nominal(), nominal()));
  }();
  return joints;
}

}  // namespace

TEST_CASE("the predicted work-volume error is the fit's covariance carried to the tool",
          "[design]") {
  const Plan plan = planCell(nominal(), smallCell());
  constexpr double kSigma = 0.084;
  const double predicted = predictedWorkVolumeError(nominal(), plan, workJoints(), kSigma);
  // Noisy lengths of the nominal robot, fitted: the solver's covariance, rescaled from its
  // estimated sigma to the true one, predicts the same RMS tool error over the same poses.
  std::vector<Sample> samples = planSamples(nominal(), plan);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0, kSigma);
  for (Sample& s : samples) s.length_mm += noise(rng);
  const SolveResult fit = solveCalibration(nominal(), samples);
  REQUIRE(fit.identifiability.rank == 36);
  const Kinematics kin(fit.params);
  const Eigen::MatrixXd c = fit.covariance * std::pow(kSigma / fit.sigma_mm, 2);
  double sum = 0;
  for (const JointsDeg& q : workJoints()) {
    PositionJacobian g;
    kin.ballPositionJacobian(q, Eigen::Vector3d::Zero(), g);
    sum += (g * c * g.transpose()).trace();
  }
  const double from_fit = std::sqrt(sum / workJoints().size());
  INFO("predicted " << predicted << " mm, from the fit's covariance " << from_fit << " mm");
  CHECK(predicted == Approx(from_fit).epsilon(0.03));
  // Halving the noise halves it; a plan with fewer points predicts more error.
  CHECK(predictedWorkVolumeError(nominal(), plan, workJoints(), kSigma / 2) ==
        Approx(predicted / 2).epsilon(1e-9));
  Plan half = plan;
  half.shells.resize(3);
  CHECK(predictedWorkVolumeError(nominal(), half, workJoints(), kSigma) > predicted);
}

TEST_CASE("a design for compliance predicts the error of a fit that also fits the twist",
          "[design][compliance]") {
  const Plan plan = planCell(nominal(), smallCell());
  constexpr double kSigma = 0.084;
  const std::vector<Sample> samples = planSamples(nominal(), plan);
  const std::vector<int> identified = identifiedParameters(nominal(), samples);
  const std::vector<int> twisted = designComplianceJoints(nominal(), samples, true);
  REQUIRE(twisted == std::vector<int>{1, 2});  // the PUMA's shoulder and elbow carry the weight
  // Independently: the twist's columns by differences of the model that twists (Kinematics with
  // a compliance), the parameters' from the analytic gradient.
  const int r = static_cast<int>(identified.size() + twisted.size());
  const Kinematics rigid(nominal());
  constexpr double kStep = 1e-5;  // deg/(N m): a few thousandths of a degree of twist
  const auto twistedBy = [&](int joint, double c) {
    Model m = nominal();
    m.compliance->deg_per_nm[joint] = c;
    return Kinematics(m);
  };
  Eigen::MatrixXd jac(samples.size(), r);
  for (size_t i = 0; i < samples.size(); ++i) {
    const Sample& s = samples[i];
    const Eigen::Vector3d& ball = nominal().balls_mm[s.ball_index];
    const Eigen::Vector3d& chuck = nominal().chucks_mm[s.chuck_index];
    ParamRow g;
    rigid.barLengthGradient(s.joints_deg, ball, chuck, g);
    for (size_t a = 0; a < identified.size(); ++a) jac(i, a) = g[identified[a]];
    for (size_t c = 0; c < twisted.size(); ++c)
      jac(i, identified.size() + c) =
          (twistedBy(twisted[c], kStep).barLength(s.joints_deg, ball, chuck) -
           twistedBy(twisted[c], -kStep).barLength(s.joints_deg, ball, chuck)) /
          (2 * kStep);
  }
  const Eigen::MatrixXd cov =
      kSigma * kSigma * (jac.transpose() * jac).ldlt().solve(Eigen::MatrixXd::Identity(r, r));
  double sum = 0;
  for (const JointsDeg& q : workJoints()) {
    PositionJacobian full;
    rigid.ballPositionJacobian(q, Eigen::Vector3d::Zero(), full);
    Eigen::MatrixXd g(3, r);
    for (size_t a = 0; a < identified.size(); ++a) g.col(a) = full.col(identified[a]);
    for (size_t c = 0; c < twisted.size(); ++c)
      g.col(identified.size() + c) =
          (twistedBy(twisted[c], kStep).ballPosition(q, Eigen::Vector3d::Zero()) -
           twistedBy(twisted[c], -kStep).ballPosition(q, Eigen::Vector3d::Zero())) /
          (2 * kStep);
    sum += (g * cov * g.transpose()).trace();
  }
  const double independent = std::sqrt(sum / workJoints().size());
  const double designed = predictedWorkVolumeError(nominal(), plan, workJoints(), kSigma, true);
  const double rigid_fit = predictedWorkVolumeError(nominal(), plan, workJoints(), kSigma);
  INFO("with the twist " << designed << " mm (independently " << independent << "), rigid fit "
                         << rigid_fit << " mm");
  CHECK(designed == Approx(independent).epsilon(1e-4));
  CHECK(designed > rigid_fit * 1.01);  // two more parameters from the same data cost something
  // A model without a load has no twist to design for.
  Model no_load = nominal();
  no_load.compliance.reset();
  CHECK_THROWS_AS(predictedWorkVolumeError(no_load, plan, workJoints(), kSigma, true),
                  std::invalid_argument);
  CHECK(designComplianceJoints(no_load, samples, false).empty());
}

TEST_CASE("an optimal plan of N points predicts less error than a grid of as many", "[design]") {
  const CellConfig cell = smallCell();
  const Plan grid = planCell(nominal(), cell);
  DesignOptions options = smallOptions();
  options.points = grid.summary.points;
  DesignReport report;
  const Plan optimal = planOptimal(nominal(), cell, workJoints(), options, &report);
  const double grid_mm = predictedWorkVolumeError(nominal(), grid, workJoints(), 0.084);
  INFO("grid " << grid.summary.points << " points: " << grid_mm << " mm; optimal "
               << optimal.summary.points << " points: " << report.predicted_rms_mm << " mm");
  CHECK(optimal.summary.points <= options.points);
  CHECK(optimal.summary.points >= options.points * 9 / 10);  // few dropped when joined
  CHECK(optimal.summary.rank == 36);
  CHECK(report.predicted_rms_mm < grid_mm);
  CHECK(report.predicted_rms_mm ==
        Approx(predictedWorkVolumeError(nominal(), optimal, workJoints(), 0.084)));
  CHECK(checkPlan(nominal(), cell, optimal).empty());
  // The same request plans the same points again.
  const Plan again = planOptimal(nominal(), cell, workJoints(), options);
  REQUIRE(again.shells.size() == optimal.shells.size());
  for (size_t s = 0; s < again.shells.size(); ++s)
    CHECK(again.shells[s].steps.size() == optimal.shells[s].steps.size());
}

TEST_CASE("a robust optimal plan trades a little of the work volume for the whole range",
          "[design]") {
  const CellConfig cell = smallCell();
  DesignOptions options = smallOptions();
  options.points = 60;
  const std::vector<JointsDeg> whole = wholeRangeJoints(*makeArm(nominal()), 100);
  const Plan knife_edge = planOptimal(nominal(), cell, workJoints(), options);
  options.whole_range_joints = whole;
  options.whole_range_weight = 0.1;
  const Plan robust = planOptimal(nominal(), cell, workJoints(), options);
  const auto predicted = [&](const Plan& plan, const std::vector<JointsDeg>& where) {
    return predictedWorkVolumeError(nominal(), plan, where, 0.084);
  };
  INFO("work volume " << predicted(knife_edge, workJoints()) << " -> "
                      << predicted(robust, workJoints()) << " mm, whole range "
                      << predicted(knife_edge, whole) << " -> " << predicted(robust, whole));
  CHECK(predicted(robust, whole) < 0.9 * predicted(knife_edge, whole));
  CHECK(predicted(robust, workJoints()) < 1.5 * predicted(knife_edge, workJoints()));
  CHECK(checkPlan(nominal(), cell, robust).empty());
  // A weight of 0, or no joint vectors, is the work volume alone: the same plan.
  options.whole_range_weight = 0;
  CHECK(predicted(planOptimal(nominal(), cell, workJoints(), options), whole) ==
        Approx(predicted(knife_edge, whole)));
  options.whole_range_weight = -1;
  CHECK_THROWS_AS(planOptimal(nominal(), cell, workJoints(), options), std::invalid_argument);
}

TEST_CASE("an optimal plan designed for compliance measures the twist better",
          "[design][compliance]") {
  const CellConfig cell = smallCell();
  DesignOptions options = smallOptions();
  options.points = 60;
  options.whole_range_joints = wholeRangeJoints(*makeArm(nominal()), 100);
  options.whole_range_weight = 1;
  const Plan rigid = planOptimal(nominal(), cell, workJoints(), options);
  options.compliance = true;
  DesignReport report;
  const Plan designed = planOptimal(nominal(), cell, workJoints(), options, &report);
  const auto withTwist = [&](const Plan& plan, const std::vector<JointsDeg>& where) {
    return predictedWorkVolumeError(nominal(), plan, where, 0.084, true);
  };
  const std::vector<JointsDeg>& whole = options.whole_range_joints;
  INFO("fit with the twist, whole range: plan designed rigid "
       << withTwist(rigid, whole) << " mm, designed for it " << withTwist(designed, whole));
  CHECK(withTwist(designed, whole) < 0.95 * withTwist(rigid, whole));
  CHECK(report.predicted_rms_mm == Approx(withTwist(designed, workJoints())));
  CHECK(checkPlan(nominal(), cell, designed).empty());
}

TEST_CASE("an optimal plan keeps its time budget, swaps included", "[design][heavy]") {
  const CellConfig cell = smallCell();
  DesignOptions options = smallOptions();
  options.budget_s = 20 * 60;
  const Plan plan = planOptimal(nominal(), cell, workJoints(), options);
  CHECK(plan.summary.cell_time_s <= options.budget_s);
  CHECK(plan.summary.cell_time_s > 0.6 * options.budget_s);  // and uses most of it
  CHECK(plan.summary.swap_time_s == Approx(plan.summary.shells * cell.motion.swap_s));
  CHECK(plan.summary.cell_time_s == Approx(plan.summary.duration_s + plan.summary.swap_time_s));
  // Its parts, as robocal plan prints them a point: they add up to the same cell time.
  const CellTimeParts parts = cellTimeParts(plan);
  CHECK(parts.total_s() == Approx(plan.summary.cell_time_s));
  CHECK(parts.points == plan.summary.points);
  CHECK(parts.stops == plan.summary.points + plan.summary.vias);
  CHECK(parts.dwell_s == Approx(plan.summary.points * cell.motion.settle_s));
  CHECK(parts.swap_s == Approx(plan.summary.swap_time_s));
  CHECK(parts.motion_s > 0);
  CHECK(plan.summary.rank == 36);
  CHECK(checkPlan(nominal(), cell, plan).empty());
  // A longer budget buys a smaller error.
  options.budget_s = 40 * 60;
  const Plan longer = planOptimal(nominal(), cell, workJoints(), options);
  CHECK(predictedWorkVolumeError(nominal(), longer, workJoints(), 0.084) <
        predictedWorkVolumeError(nominal(), plan, workJoints(), 0.084));
  CHECK_THROWS_AS(planOptimal(nominal(), cell, workJoints(), smallOptions()), PlanError);
}

TEST_CASE("through vias, a plan's vias cost their travel, and a blended corner too far stops",
          "[design]") {
  CellConfig cell = smallCell();
  cell.connections = parseConnections("B1C2");
  const Plan stopping = planCell(nominal(), cell);
  cell.motion.through_vias = true;
  cell.motion.blend_deg = 0;  // corners not cut: every via passed through
  const Plan through = planCell(nominal(), cell);
  // The same steps (the vias still keep the nominal bar within via_tolerance_mm), cheaper.
  REQUIRE(through.summary.points == stopping.summary.points);
  REQUIRE(through.summary.vias == stopping.summary.vias);
  REQUIRE(stopping.summary.vias > 0);
  CHECK(through.summary.duration_s ==
        Approx(stopping.summary.duration_s - stopping.summary.vias * cell.motion.move_overhead_s));
  const CellTimeParts parts = cellTimeParts(through);
  CHECK(parts.stops == through.summary.points);
  CHECK(parts.total_s() == Approx(through.summary.cell_time_s));
  CHECK(cellTimeParts(stopping).motion_s == Approx(parts.motion_s));
  CHECK(checkPlan(nominal(), cell, through).empty());

  // Blended corners: where the path cut inside a via would leave the bar's tolerance, the arm
  // stops at that via; the more the blend, the more such vias; every plan passes its check.
  const auto stopsOf = [](const Plan& p) {
    int n = 0;
    for (const ShellPlan& sh : p.shells)
      for (const PlanStep& st : sh.steps) n += st.kind == StepKind::kVia && st.stop;
    return n;
  };
  CHECK(stopsOf(through) == 0);
  cell.motion.blend_deg = 2;
  const Plan blended = planCell(nominal(), cell);
  cell.motion.blend_deg = 10;
  const Plan wide = planCell(nominal(), cell);
  CHECK(stopsOf(blended) <= stopsOf(wide));
  CHECK(stopsOf(wide) > 0);
  CHECK(stopsOf(wide) < wide.summary.vias);
  CHECK(cellTimeParts(wide).stops == wide.summary.points + stopsOf(wide));
  CHECK(checkPlan(nominal(), cell, wide).empty());
  // The plan without those stops, run with that blend, is refused.
  Plan unsafe = through;
  unsafe.cell.motion.blend_deg = 10;
  CHECK_FALSE(checkPlan(nominal(), cell, unsafe).empty());

  // The cell file keeps the choice; a stop flag survives the plan file.
  const CellConfig back = cellFromJson(nlohmann::json::parse(cellToJson(cell).dump()));
  CHECK(back.motion.through_vias);
  CHECK(back.motion.blend_deg == 10);
  CHECK_FALSE(
      cellFromJson(nlohmann::json::parse(cellToJson(smallCell()).dump())).motion.through_vias);
  CHECK(stopsOf(planFromJson(nlohmann::json::parse(planToJson(wide).dump()))) == stopsOf(wide));
}

TEST_CASE("a short tour visits every point once and is no longer than the given order",
          "[design]") {
  const CellConfig cell = smallCell();
  const ShellPlanner planner(nominal(), cell);
  const ShellCandidates cand =
      planner.candidatePoints(cell.connections[0], 0, smallOptions().candidate_grid, 1);
  REQUIRE(cand.connect);
  REQUIRE(cand.points.size() > 10);
  std::vector<ShellPoint> shuffled = cand.points;
  std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(7));
  auto length = [&](const std::vector<size_t>& order) {
    double t = 0;
    JointsDeg here = cand.connect->joints_deg;
    for (size_t i : order) {
      t += planner.moveDuration(here, shuffled[i].joints_deg);
      here = shuffled[i].joints_deg;
    }
    return t;
  };
  const std::vector<size_t> tour = shortTour(planner, cand.connect->joints_deg, shuffled);
  std::vector<size_t> sorted = tour, given(shuffled.size());
  std::sort(sorted.begin(), sorted.end());
  std::iota(given.begin(), given.end(), 0);
  CHECK(sorted == given);
  CHECK(length(tour) < 0.6 * length(given));
}
