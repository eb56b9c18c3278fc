// One plan pipeline for robocal plan and robocald alike (issue 23): a cell's plan (its grid, an
// optimal plan within a budget or a number of points, or the health check), with what a plan's
// summary says of it: its identifiability, its predicted error where the user works and over the
// arm's whole range, and the deflection forecast (docs/plan-format.md). Math only, no I/O: the
// callers write the plan file and print or send the summary.
#pragma once

#include <robocal/kinematics/model.hpp>
#include <robocal/planner/cell.hpp>
#include <robocal/planner/design.hpp>
#include <robocal/planner/plan.hpp>

#include <cstddef>

namespace robocal {

enum class PlanKind {
  kGrid,     // the cell's grid on every connection and extension
  kOptimal,  // planOptimal within design.budget_s or design.points
  kCheck,    // the health check of the calibrated cell (health_plan.hpp)
};

struct PlanRequest {
  PlanKind kind = PlanKind::kGrid;
  // The budget of an optimal plan, the bar's noise for the predicted errors, the whole range's
  // weight in an optimal plan's objective (design.hpp).
  DesignOptions design;
};

struct PlannedCell {
  Plan plan;                   // summary filled: rank, predicted errors (not for a check), forecast
  CellConfig cell;             // the cell it was planned with (a check's own: healthCheckCell)
  std::size_t work_poses = 0;  // poses of the work volume the error is predicted over
  std::size_t whole_poses = 0;  // joint vectors of the whole range
  DesignReport design_report;   // kOptimal only
  // The forecast needs a nominal model's uncertainty (the cell's model_uncertainty): a check
  // planned with a calibrated model (one with a provenance) gets none.
  bool forecast = false;
};

// Throws PlanError when the cell cannot be planned, std::invalid_argument when its work volume
// is out of the arm's reach.
PlannedCell planCalibration(const Model& model, const CellConfig& calibration_cell,
                            const PlanRequest& request);

}  // namespace robocal
