// The health check's plan (docs/health-check.md): a short verification run derived from the
// calibration cell, to tell whether the calibrated model still fits the robot (after a crash, a
// motor swap, wear). Three connections that together use every ball and every chuck, one bar
// extension the calibration did not use (so the check predicts shells the fit never saw), and a
// coarse grid: about ten minutes in all. No I/O.
#pragma once

#include <robocal/kinematics/model.hpp>
#include <robocal/planner/cell.hpp>
#include <robocal/planner/plan.hpp>

#include <vector>

namespace robocal {

// The check's grid: latitudes 30 and 70 deg, longitudes every 30 deg from the calibration's first
// longitude: 24 grid points a shell, 72 in all, about 7 minutes of robot time on the reference
// cell (docs/health-check.md: with the operator's three connections, about 10 minutes).
inline constexpr double kHealthCheckLatitudeFirstDeg = 30;
inline constexpr double kHealthCheckLatitudeLastDeg = 70;
inline constexpr double kHealthCheckLatitudeStepDeg = 40;
inline constexpr double kHealthCheckLongitudeStepDeg = 30;
// The operator's time per shell that the check's total assumes: take the bar off the previous
// connection, seat it on the next, confirm (the first with the check's extension put on).
inline constexpr double kHealthCheckOperatorMinPerShell = 1.0;

// The check's extension: the midpoint of the widest gap between the calibration's extensions
// (sorted; 75 mm for [0, 150]), or, when the calibration used one extension e, e plus half the
// bar's nominal length. Never one of the calibration's.
double healthCheckExtension(const BarSettings& calibration);

// Three of the calibration's connections that together use every ball and every chuck, the first
// such in the order B1C2 B2C3 B3C1, B1C3 B2C1 B3C2, B1C1 B2C2 B3C3, then the other three
// matchings. Throws PlanError when the calibration's connections hold no such three.
std::vector<Connection> healthCheckConnections(const std::vector<Connection>& calibration);

// The verification cell: the calibration cell with healthCheckConnections, the one extension
// healthCheckExtension and the check's grid; bar, tool policy, margins, motion and uncertainty
// unchanged. Throws PlanError as healthCheckConnections does.
CellConfig healthCheckCell(const CellConfig& calibration);

// Plans the check: planCell(model, healthCheckCell(calibration)) with purpose kCheck and the
// identification summary (summarizeIdentifiability) filled in. Throws PlanError.
Plan planHealthCheck(const Model& model, const CellConfig& calibration);

}  // namespace robocal
