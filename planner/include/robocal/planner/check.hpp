// Re-verification of any plan (hand-edited ones too) against the safety rules of a model and a
// cell: what `robocal check-plan` prints and what the daemon runs before it moves anything.
// No I/O.
#pragma once

#include <robocal/planner/plan.hpp>

#include <string>
#include <vector>

namespace robocal {

inline constexpr int kConnectStep = -1;  // PlanViolation::step of the connect pose
inline constexpr int kShellStep = -2;    // PlanViolation::step of the shell (or plan) as a whole

struct PlanViolation {
  int shell = 0;          // the shell's number as written in the plan (0 for the plan as a whole)
  int step = kShellStep;  // 0-based index into the shell's steps, or kConnectStep, kShellStep
  std::string rule;       // short name: "limits", "deviation", "configuration", ...
  std::string message;    // what is wrong, with numbers
};

// Every rule the planner keeps, checked from the joints alone with `model`:
//   - each shell's connection, extension (one of the cell's) and radius (bar + extension);
//   - at the connect pose and every step: joints inside the limits minus the margin, the
//     singularity margins, the bar-tool angle, the table clearance, the shell's arm
//     configuration, |radial deviation| <= via_tolerance_mm, and the ball at the step's stated
//     latitude and longitude (within 1 mm);
//   - along every joint-interpolated segment (connect -> step 0 -> step 1 ...), sampled at
//     motion.sample_step_mm or finer: the same pose rules.
// One violation per broken rule per step (the first sample of a segment that breaks it).
// Throws PlanError when the model or the cell cannot be used at all.
std::vector<PlanViolation> checkPlan(const Model& model, const CellConfig& cell, const Plan& plan);

// "shell 3 step 17 (deviation): ..." / "shell 3 connect pose (limits): ..." /
// "shell 3 (radius): ...".
std::string describeViolation(const PlanViolation& v);

}  // namespace robocal
