// robocal plan: the off-line plan of the ball-bar shells (docs/plan-format.md).
#include "args.hpp"

#include <robocal/calibration/plan_pipeline.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/planner/cell_json.hpp>
#include <robocal/planner/design.hpp>
#include <robocal/planner/health_plan.hpp>
#include <robocal/planner/plan.hpp>
#include <robocal/planner/plan_json.hpp>
#include <robocal/planner/swaps.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace robocal::cli {
namespace {

// The whole range's share of an optimal plan's objective (docs/cell-time.md, "Robust plans").
constexpr double kWholeRangeWeight = 0.1;

constexpr const char* kHelp =
    R"(usage: robocal plan --model M --cell C [--out plan.json] [--check]
                    [--time-budget-min M | --points N] [options]

Plans the ball-bar shells of a cell with the given (nominal) model: data points on each
connection's shell, tool orientations, and via points that keep the bar within the cell's
via_tolerance_mm along every joint-interpolated move. Prints a summary per shell, the dropped
points, the identification rank and condition number, and the bar deflection forecast for the
cell's model_uncertainty.

With --check, plans the health check of the calibrated cell instead (docs/health-check.md):
two connections, one extension between the cell's, 30 points chosen where the changes it must
see (0.02 deg on joints 1-3, 0.05 deg on 4-6, 0.1 mm on a link) move the bar most; about 5
minutes with the operator's steps. Give the calibrated model in use as
--model, and the calibration's cell.

With --time-budget-min or --points, plans an optimal calibration instead of the cell's grid
(docs/plan-format.md, "Optimal plans"): points chosen from a dense grid of safe candidates on
every connection and extension to make the calibrated model most accurate over the cell's
work_volume, within that much cell time (moves, dwells and the operator's swaps) or that many
points. Every plan's summary ends with its predicted work-volume error and its cell time.

  --model FILE     robot model (model format)                                  required
  --cell FILE      cell settings (docs/cell-format.md)                         required
  --out FILE       plan to write (docs/plan-format.md)             [plan.json; check.json]
  --check          the health check's plan (purpose "check")
  --time-budget-min M  optimal plan within M minutes of cell time
  --points N       optimal plan of N points
  --noise-mm S     the bar's reading noise for the predicted error            [0.084]
  --whole-range-weight W  an optimal plan's objective is sqrt(work^2 + W whole^2): the
                   predicted error in the work volume and over the arm's whole range, so
                   that the plan stays robust off its volume; 0: the work volume alone  [0.1]
  --compliance     plan for a fit that also identifies the gravity compliance of the joints
                   carrying the arm's weight (as robocal solve does): their twist is
                   designed for and its uncertainty is in the predicted errors. The
                   default when the model has its "compliance" load; with this option a
                   model without it is refused
  --rigid          plan for a fit of the 54 parameters alone (robocal solve --rigid)
  --quiet          print only the totals, not each shell and dropped point
)";

int run(const std::vector<std::string>& argv) {
  const Args args(
      argv, {"model", "cell", "out", "time-budget-min", "points", "noise-mm", "whole-range-weight"},
      {"help", "quiet", "check", "compliance", "rigid"});
  if (args.flag("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  if (!args.positional().empty())
    throw UsageError("unexpected argument '" + args.positional()[0] + "'");
  const Model model = loadModelFile(args.required("model"));
  const bool check = args.flag("check");
  const CellConfig calibration_cell = loadCellFile(args.required("cell"));
  const std::string out = args.get("out", check ? "check.json" : "plan.json");
  const bool quiet = args.flag("quiet");
  DesignOptions design;
  design.budget_s = 60 * args.number("time-budget-min", 0);
  design.points = static_cast<int>(args.number("points", 0));
  design.noise_sigma_mm = args.number("noise-mm", design.noise_sigma_mm);
  design.whole_range_weight = args.number("whole-range-weight", kWholeRangeWeight);
  if (args.flag("compliance") && args.flag("rigid"))
    throw UsageError("--compliance and --rigid: give one");
  // A calibration is fitted with the twist when the model has the load (robocal solve's default).
  design.compliance =
      args.flag("compliance") || (!args.flag("rigid") && !check && model.compliance.has_value());
  if (design.budget_s < 0 || design.points < 0 || design.noise_sigma_mm <= 0 ||
      !(design.whole_range_weight >= 0))
    throw UsageError(
        "--time-budget-min, --points and --whole-range-weight must be >= 0, --noise-mm > 0");
  const bool optimal = design.budget_s > 0 || design.points > 0;
  if (optimal && check) throw UsageError("--check plans a fixed health check: no budget");
  if (check && args.flag("compliance"))
    throw UsageError("--compliance designs a calibration; a health check is not fitted");
  if (design.compliance && !model.compliance) {
    std::fprintf(stderr,
                 "robocal plan: %s: --compliance needs the model's \"compliance\" load (link "
                 "masses, the fixture; docs/model-format.md)\n",
                 args.required("model").c_str());
    return 2;
  }

  PlanRequest request;
  request.kind = optimal ? PlanKind::kOptimal : check ? PlanKind::kCheck : PlanKind::kGrid;
  request.design = design;
  const auto t0 = std::chrono::steady_clock::now();
  PlannedCell planned;
  try {
    planned = planCalibration(model, calibration_cell, request);
  } catch (const std::invalid_argument& e) {  // the work volume is out of reach
    std::fprintf(stderr, "robocal plan: cannot plan: work_volume: %s\n", e.what());
    return 1;
  } catch (const PlanError& e) {
    std::fprintf(stderr, "robocal plan: cannot plan: %s\n", e.what());
    return 1;
  }
  const double plan_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const Plan& plan = planned.plan;
  const CellConfig& cell = planned.cell;
  const double predicted_mm = plan.summary.predicted_work_volume_error_mm;
  const double whole_mm = plan.summary.predicted_whole_range_error_mm;
  const bool forecast = planned.forecast;
  const ModelUncertainty& u = cell.uncertainty;
  const DesignReport& design_report = planned.design_report;
  savePlanFile(out, plan);

  if (!quiet) {
    for (const ShellPlan& s : plan.shells) {
      std::printf(
          "shell %2d %s ext %5.1f mm r %5.1f mm %-16s %3d points %4d vias %2zu dropped  %5.1f min  "
          "deviation <= %.3f mm",
          s.shell, connectionName(s.connection).c_str(), s.extension_mm, s.radius_mm,
          armConfigName(s.config).c_str(), s.summary.points, s.summary.vias, s.dropped.size(),
          s.summary.duration_s / 60.0, s.summary.max_deviation_mm);
      if (s.summary.predicted_deflection_mm >= 0)
        std::printf("  deflection <= %.2f mm (change from connect <= %.2f mm)%s",
                    s.summary.predicted_deflection_mm, s.summary.predicted_change_mm,
                    s.summary.predicted_change_mm > cell.bar.max_deflection_mm
                        ? "  BEYOND THE BAR'S RANGE"
                        : "");
      std::printf("\n");
    }
    for (const ShellPlan& s : plan.shells)
      for (const DroppedPoint& d : s.dropped)
        std::printf("  dropped: shell %d lat %5.1f lon %5.1f deg: %s\n", s.shell, d.lat_deg,
                    d.lon_deg, d.reason.c_str());
  }
  const PlanSummary& sum = plan.summary;
  if (check) {
    std::vector<Connection> connections;
    for (const ShellPlan& s : plan.shells) connections.push_back(s.connection);
    std::printf(
        "check plan: %d points on %d shells (%s), extension %g mm (the calibration's: ", sum.points,
        sum.shells, connectionList(connections).c_str(), cell.bar.extension_lengths_mm.front());
    for (size_t i = 0; i < calibration_cell.bar.extension_lengths_mm.size(); ++i)
      std::printf("%s%g", i ? ", " : "", calibration_cell.bar.extension_lengths_mm[i]);
    std::printf(
        " mm); about %.1f min of robot time at %.0f deg/s with %.1f s dwell, plus the operator's "
        "%d connections: about %.1f min in all\n",
        sum.duration_s / 60.0, cell.motion.joint_speed_deg_per_s, cell.motion.settle_s, sum.shells,
        sum.duration_s / 60.0 + sum.shells * kHealthCheckOperatorMinPerShell);
    std::printf(
        "check design: points where %g deg on joints 1-3, %g deg on joints 4-6 and %g mm on a "
        "link stand out most from the bar's noise and from what the calibration left uncertain "
        "(a check is judged, not fitted: its rank does not matter)\n",
        kHealthCheckJoint13Deg, kHealthCheckJoint46Deg, kHealthCheckTranslationMm);
  }
  std::printf(
      "plan: %d shells, %d points, %d vias, %d grid points dropped; about %.1f %s at %.0f "
      "deg/s with %.1f s dwell; nominal deviation <= %.3f mm (tolerance %.3f mm)\n",
      sum.shells, sum.points, sum.vias, sum.dropped,
      check ? sum.duration_s / 60.0 : sum.duration_s / 3600.0, check ? "min" : "h",
      cell.motion.joint_speed_deg_per_s, cell.motion.settle_s, sum.max_deviation_mm,
      cell.motion.via_tolerance_mm);
  std::printf("identification: rank %d of %d, condition number %.3g", plan.summary.rank,
              plan.summary.expected_rank, plan.summary.condition_number);
  for (double e : cell.bar.extension_lengths_mm) {
    const PlanIdentifiability part = planIdentifiability(model, plan, e);
    std::printf("; extension %.0f mm alone: rank %d, condition %.3g", e, part.rank,
                part.condition_number);
  }
  std::printf("\n");
  if (!forecast)
    std::printf(
        "forecast: none: the cell's model_uncertainty is that of a nominal model, and this check "
        "is planned with a calibrated one (the daemon's centring keeps the bar in range if the "
        "robot has changed)\n");
  if (sum.predicted_deflection_mm >= 0)
    std::printf(
        "forecast: with model errors of %.2f mm / %.3f deg (links), %.3f deg (joint "
        "offsets), %.4f (gains) over %d simulated robots, the bar deflects up to %.2f mm "
        "from its nominal length and changes by up to %.2f mm from its reading at the "
        "connect pose (range +/-%.2f mm)\n",
        u.translation_sigma_mm, u.link_angle_sigma_deg, u.joint_offset_sigma_deg, u.gain_sigma,
        u.models, sum.predicted_deflection_mm, sum.predicted_change_mm, cell.bar.max_deflection_mm);
  if (!check && plan.summary.rank < plan.summary.expected_rank)
    std::printf("warning: the plan identifies only %d of the %d independent parameters\n",
                plan.summary.rank, plan.summary.expected_rank);
  if (sum.predicted_change_mm > cell.bar.max_deflection_mm)
    std::printf(
        "warning: with that model error the bar can leave its range: run it with the "
        "model refined as data arrive (the daemon re-plans the rest of each shell), or "
        "calibrate roughly first\n");
  char predicted_text[32];
  std::snprintf(predicted_text, sizeof predicted_text, "%.4f mm", predicted_mm);
  if (!check)
    std::printf(
        "work volume: predicted RMS tool position error %s after the fit (bar noise %.3f "
        "mm, %zu poses); cell time %.1f min: robot %.1f min, %d bar swaps %.1f min\n",
        predicted_mm >= 0 ? predicted_text : "none (the plan does not identify the model)",
        design.noise_sigma_mm, planned.work_poses, sum.cell_time_s / 60.0, sum.duration_s / 60.0,
        sum.shells, sum.swap_time_s / 60.0);
  if (const CellTimeParts parts = cellTimeParts(plan); parts.points > 0) {
    const double n = parts.points;
    std::printf(
        "cell time a point: %.2f s = dwell %.2f + moves %.2f + stops %.2f (%.1f stops a point: "
        "%s, %.1f s each) + bar swaps %.2f\n",
        parts.total_s() / n, parts.dwell_s / n, parts.motion_s / n, parts.stopping_s / n,
        parts.stops / n,
        cell.motion.through_vias ? "the point; its vias passed through"
                                 : "the point, its vias and pre-points",
        cell.motion.move_overhead_s, parts.swap_s / n);
  }
  std::printf("operator: %s\n", describeOperatorSteps(operatorSteps(model, plan)).c_str());
  if (!check && whole_mm >= 0 && predicted_mm > 0)
    std::printf(
        "whole range: predicted RMS tool position error %.4f mm after the fit over %zu joint "
        "vectors within the arm's limits (%.1fx the work volume's: what this plan does not "
        "cover)\n",
        whole_mm, planned.whole_poses, whole_mm / predicted_mm);
  if (optimal)
    std::printf("optimal: %d points chosen from %d candidates in %d round%s%s\n", sum.points,
                design_report.candidates, design_report.rounds,
                design_report.rounds == 1 ? "" : "s",
                design.budget_s > 0 && sum.cell_time_s > design.budget_s
                    ? ("; OVER THE BUDGET (the fewest points that reach rank " +
                       std::to_string(sum.expected_rank) + " take longer)")
                          .c_str()
                    : "");
  std::printf("planned in %.2f s; wrote %s\n", plan_s, out.c_str());
  return 0;
}

const RegisterCommand registered({"plan", "plan the ball-bar shells, their points and vias", run});

}  // namespace
}  // namespace robocal::cli
