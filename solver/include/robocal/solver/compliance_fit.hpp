// Gravity compliance identified with the 54 parameters (docs/accuracy.md, "Compliance"): the
// twist per N m of the joints that carry the arm's weight, from the same ball-bar samples, with the
// load (link masses and centres, the fixture) as input (Model::compliance's load).
//
// Over a calibration's shells a joint's twist follows its gravity torque, which changes slowly
// with the pose: the joint offsets and gains absorb most of it, and what they cannot absorb is
// what identifies it. The fit is a variable projection: for a compliance c the 54 parameters are
// fitted (solveCalibration, the model evaluated at the twisted readings), and c moves along the
// Gauss-Newton step of those fits' residuals, whose Jacobian is taken by differences (one fit per
// joint). The residual is nearly linear in c: two steps reach it. Its covariance is the fit's
// sigma^2 (J^T J)^-1 with J that projected Jacobian: what the data say about c once the 54
// parameters have taken what they can; the twist is kept only when it stands out of it. The
// joint covariance of the 54 and the twist (for the predicted errors) adds what each twist moves
// the 54 by: the 54's own at the fitted twist plus A C_c A^T, A = d params / d twist. Math only.
#pragma once

#include <robocal/solver/calibrate.hpp>

#include <array>
#include <string>
#include <vector>

namespace robocal {

// What a twist can be before any data (docs/realism.md's sources: 0.01-0.05 deg at the largest
// gravity torque of a geared arm's shoulder and elbow): the predicted errors count a twist's
// uncertainty at most about this size.
inline constexpr double kPriorLargestTwistDeg = 0.03;
// kPriorLargestTwistDeg per each joint's largest gravity torque within its limits (deg/(N m));
// 0 for a joint that carries none. Zeros for a model without a load.
std::array<double, kJointCount> priorTwistSigmaDegPerNm(const Model& start);

struct ComplianceEstimate {
  // The start's load with the twist per N m the model takes: the fitted one when identified,
  // else the start's.
  JointCompliance compliance;
  std::array<double, kJointCount> fitted_deg_per_nm{};  // what the data show, kept or not
  // 1-sigma of each joint's twist per N m (deg/(N m)); 0 for the joints not identified.
  std::array<double, kJointCount> sigma_deg_per_nm{};
  std::vector<int> joints;  // fitted (0-based), those carrying the weight
  // Whether the twist the data show stands out of its uncertainty: its chi-square (the change from
  // the start's twist, weighed by its covariance) above the quantile at 1e-3 for its joints. When
  // it does not, the model keeps the start's twist (a rigid arm stays rigid): a twist the data
  // cannot tell from noise would only move the arm's whole range by that noise.
  bool identified = false;
  double chi2 = 0, chi2_threshold = 0;
  // The joint covariance of the 54 parameters and the six joints' twists, in Model::covariance's
  // layout (kParamCount + kJointCount square; ParamVector units, then deg/(N m)): the twist's
  // covariance (the data's, bounded by the prior, priorTwistSigmaDegPerNm), what it moves the 54
  // by (the fit absorbs part of a twist), and the 54's own at the twist the model takes; each
  // joint not fitted, as compliant as the most compliant fitted one. Also when the twist is not
  // kept: a twist the data cannot tell from noise may still be there up to its uncertainty, and the
  // predicted errors count it (a rigid prediction of the arm's whole range is then 2-5x short of
  // the truth: docs/accuracy.md). Empty when no joint carries the weight.
  Eigen::MatrixXd covariance;
  // The largest twist over the samples' poses (deg) and its 1-sigma: what the compliance means.
  double largest_twist_deg = 0;
  double largest_twist_sigma_deg = 0;
  int fits = 0;  // solveCalibration calls
  // In words: "joint 2 0.00071 +/- 0.00004, joint 3 0.0015 +/- 0.0001 deg/(N m): up to 0.031
  // +/- 0.002 deg of twist at these poses", or why it was not kept.
  std::string summary() const;
};

// The joints a compliance is identified for: those whose gravity torque over the samples' poses
// has an RMS of at least a tenth of the largest joint's (joints 2 and 3 of a PUMA), from the
// start model's load.
std::vector<int> loadedJoints(const Model& start, const std::vector<Sample>& samples);
// The same from each joint's RMS torque (N m).
std::vector<int> loadedJoints(const std::array<double, kJointCount>& rms_torque_nm);

// Fits the 54 parameters and the loaded joints' compliance from `start`, whose compliance gives
// the load (and the starting twist): the fit of the 54 at the identified compliance, which
// `estimate` receives. Throws std::invalid_argument when `start` has no compliance load, and as
// solveCalibration does.
SolveResult solveWithCompliance(const Model& start, const std::vector<Sample>& samples,
                                const SolveOptions& options, ComplianceEstimate& estimate);

}  // namespace robocal
