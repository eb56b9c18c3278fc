// robocal check-plan: re-verifies a plan file against the safety rules (docs/plan-format.md).
#include "args.hpp"

#include <robocal/formats/model_json.hpp>
#include <robocal/planner/cell_json.hpp>
#include <robocal/planner/check.hpp>
#include <robocal/planner/health_plan.hpp>
#include <robocal/planner/plan_json.hpp>

#include <cstdio>
#include <nlohmann/json.hpp>

namespace robocal::cli {
namespace {

constexpr const char* kHelp = R"(usage: robocal check-plan --model M --cell C PLAN

Re-verifies a plan (hand-edited ones too) with the model and the cell's rules: joint limits minus
the margin, singularity margins, bar-tool angle, table clearance, one arm configuration per
shell, the ball at each step's latitude and longitude, and the bar's radial deviation within
via_tolerance_mm along every joint-interpolated move (sampled at sample_step_mm). Prints every
violation with its shell and step index; exits 1 when there is any, 0 when the plan is safe.
A health check's plan (robocal plan --check) is checked with the calibration's cell: its shells
may use the cell's check extension (docs/health-check.md).

  --model FILE     robot model (model format)                                  required
  --cell FILE      cell settings (docs/cell-format.md)                         required
)";

int run(const std::vector<std::string>& argv) {
  const Args args(argv, {"model", "cell"}, {"help"});
  if (args.flag("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  if (args.positional().size() != 1) throw UsageError("expected one plan file");
  const Model model = loadModelFile(args.required("model"));
  const CellConfig cell = loadCellFile(args.required("cell"));
  const std::string path = args.positional()[0];
  const Plan plan = loadPlanFile(path);

  // A check plan's settings are the check cell derived from the calibration's (health_plan.hpp).
  CellConfig expected = cell;
  if (plan.purpose == PlanPurpose::kCheck) {
    try {
      expected = healthCheckCell(cell);
    } catch (const PlanError&) {
      // The cell's connections hold no check: the note below says the settings differ.
    }
  }
  if (cellToJson(plan.cell) != cellToJson(expected))
    std::printf("note: %s was made with other settings than %s%s; checking against the latter\n",
                path.c_str(), plan.purpose == PlanPurpose::kCheck ? "the check cell of " : "",
                args.required("cell").c_str());
  std::vector<PlanViolation> violations;
  try {
    violations = checkPlan(model, cell, plan);
  } catch (const PlanError& e) {
    std::fprintf(stderr, "robocal check-plan: cannot check: %s\n", e.what());
    return 1;
  }
  for (const PlanViolation& v : violations) std::printf("%s\n", describeViolation(v).c_str());
  int steps = 0;
  for (const ShellPlan& s : plan.shells) steps += static_cast<int>(s.steps.size()) + 1;
  if (!violations.empty()) {
    std::printf("%s: %zu violations (%zu shells, %d poses checked)\n", path.c_str(),
                violations.size(), plan.shells.size(), steps);
    return 1;
  }
  char blended[120] = "";
  if (plan.cell.motion.through_vias)
    std::snprintf(blended, sizeof blended,
                  ", and so does the path blended through the vias (blend %.1f deg)",
                  plan.cell.motion.blend_deg);
  std::printf(
      "%s: OK: %zu shells, %d poses and every move between them keep the rules "
      "(deviation within +/-%.3f mm)%s\n",
      path.c_str(), plan.shells.size(), steps, cell.motion.via_tolerance_mm, blended);
  return 0;
}

const RegisterCommand registered({"check-plan", "re-verify a plan file against the safety rules",
                                  run});

}  // namespace
}  // namespace robocal::cli
