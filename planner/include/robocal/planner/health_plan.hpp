// The health check's plan (docs/health-check.md): a five-minute verification run derived from the
// calibration cell, to tell whether the calibrated model still fits the robot (after a crash, a
// motor swap, wear). Two connections (two balls on two chucks), one bar extension the
// calibration did not use (so the check predicts shells the fit never saw), and 30 points chosen
// for detection: where the changes the check must see (0.02 deg on joints 1-3, 0.05 deg on
// joints 4-6, 0.1 mm on a link) move the bar most, each parameter's signature made strong. No I/O.
#pragma once

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/model.hpp>
#include <robocal/planner/cell.hpp>
#include <robocal/planner/plan.hpp>

#include <Eigen/Core>
#include <vector>

namespace robocal {

// The check's size: points over its shells, and the shells (connections, one swap each).
inline constexpr int kHealthCheckPoints = 30;
inline constexpr int kHealthCheckShells = 2;
// The grid the points are chosen from (every 10 deg of latitude and 20 of longitude, three tool
// orientations each).
inline constexpr GridSettings kHealthCheckCandidateGrid{10, 80, 10, 0, 20};
inline constexpr int kHealthCheckOrientations = 3;
// The changes the check is designed to detect (docs/health-check.md, "The plan").
inline constexpr double kHealthCheckJoint13Deg = 0.02;
inline constexpr double kHealthCheckJoint46Deg = 0.05;
inline constexpr double kHealthCheckTranslationMm = 0.1;
// The bar noise the design assumes when the model gives none (its fit's RMS): the main job's bar
// (robocal-cellsim's, a good LVDT bar's), at which the sizes above are to be detected.
inline constexpr double kHealthCheckDesignNoiseMm = 0.035;
// The operator's time per shell that the check's total assumes: take the bar off the previous
// connection, seat it on the next, confirm (the first with the check's extension put on).
inline constexpr double kHealthCheckOperatorMinPerShell = 1.0;
// What the whole check should take, the operator's swaps included.
inline constexpr double kHealthCheckMinutes = 5.0;

// What the verdict's test of a change of each parameter sees over a sequence of check points:
// its noncentrality S_k = d_k^2 e_k^T J^T (sigma^2 I + J C J^T)^-1 J e_k, J the points' bar
// gradients, C the active model's covariance (solver/health.hpp whitens the check's residuals by
// it: what the calibration left uncertain is not a change). Taken point by point, as a Kalman
// filter would: a point's reading, less what the points before it taught of the model's error,
// carries g (I - D) d of the change (D: the share of it those points took for the model's error)
// over a variance sigma^2 + g C' g^T (C': the model's covariance after them). With C = 0, the sum
// of (g d_k / sigma)^2. Math only.
class CheckSignatures {
 public:
  // `targets`: d_k / sigma per parameter (ParamVector units per mm), 0 for those not looked
  // for; `covariance_over_noise`: C / sigma^2 (54 x 54).
  CheckSignatures(const ParamVector& targets, const Eigen::MatrixXd& covariance_over_noise);
  // What each of the points whose bar gradients are the rows of `gradients` (n x 54) would add
  // to each S_k, taken next (n x 54).
  Eigen::ArrayXXd gains(const Eigen::MatrixXd& gradients) const;
  void add(const ParamRow& gradient);
  const Eigen::ArrayXd& noncentrality() const { return noncentrality_; }
  // min_k S_k over the parameters looked for.
  double weakest() const;

 private:
  ParamVector targets_;
  Eigen::ArrayXd noncentrality_;
  Eigen::MatrixXd unabsorbed_;  // I - D
  Eigen::MatrixXd covariance_;  // C' / sigma^2
};

// The signatures the check on healthCheckCell(calibration) is designed with, before any point:
// targets the changes below over the bar's noise sigma (the model's fit RMS; else, with a
// covariance, the verdict's fallback 0.084 mm; else kHealthCheckDesignNoiseMm), C the model's
// covariance, or, for a model without one (a nominal, planned before the calibration exists),
// the covariance a fit of the calibration cell's grid would leave, (J^T J)^-1 on the parameters
// it identifies: the calibrated model the check will be judged with.
CheckSignatures healthCheckSignatures(const Model& model, const CellConfig& calibration);

// The check's extension: the midpoint of the widest gap between the calibration's extensions
// (sorted; 75 mm for [0, 150]), or, when the calibration used one extension e, e plus half the
// bar's nominal length. Never one of the calibration's.
double healthCheckExtension(const BarSettings& calibration);

// Three of the calibration's connections that together use every ball and every chuck, the first
// such in the order B1C2 B2C3 B3C1, B1C3 B2C1 B3C2, B1C1 B2C2 B3C3, then the other three
// matchings. Throws PlanError when the calibration's connections hold no such three.
std::vector<Connection> healthCheckConnections(const std::vector<Connection>& calibration);

// The verification cell: the calibration cell with the first kHealthCheckShells of
// healthCheckConnections, the one extension healthCheckExtension and the candidate grid; bar,
// tool policy, margins, motion and uncertainty unchanged. Throws PlanError as
// healthCheckConnections does.
CellConfig healthCheckCell(const CellConfig& calibration);

// Plans the check on healthCheckCell(calibration): kHealthCheckPoints points, shared equally by
// its shells, chosen greedily from each shell's safe candidates to raise sum_k log(1 + S_k)
// (healthCheckSignatures: every joint offset and link translation), so that no parameter's
// signature is left weak; each shell's points in a short tour, joined by the
// ordinary planner (every safety rule of docs/plan-format.md). Purpose kCheck, with the
// identification summary (summarizeIdentifiability). Throws PlanError.
Plan planHealthCheck(const Model& model, const CellConfig& calibration);

}  // namespace robocal
