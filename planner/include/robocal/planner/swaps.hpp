// The operator's part of a plan (issue 24, "swaps ordered to shorten the operator's walk"): at
// each new shell the operator takes the bar off and connects it again; where the chuck changes
// they walk to it across the table, where only the ball or the extension changes they do not.
// The cell's `connections` are run in their listed order (docs/cell-format.md), so the order is
// the cell file's to choose; this counts what it costs, for `robocal plan` to print. The swap
// time itself stays the cell's flat motion.swap_s a shell (plan.hpp, cellTimeParts). Math only.
#pragma once

#include <robocal/kinematics/model.hpp>
#include <robocal/planner/plan.hpp>

#include <string>

namespace robocal {

struct OperatorSteps {
  int connects = 0;           // shells: the bar connected once for each
  int chuck_changes = 0;      // shells whose chuck is not the one before's: a walk
  double walk_mm = 0;         // the distance between those chucks' centres, summed
  int ball_changes = 0;       // shells whose ball is not the one before's
  int extension_changes = 0;  // shells whose bar extension is not the one before's
};

OperatorSteps operatorSteps(const Model& model, const Plan& plan);

// "18 connects: 4 walks to another chuck (1.2 m), 12 ball changes, 1 extension change".
std::string describeOperatorSteps(const OperatorSteps& steps);

}  // namespace robocal
