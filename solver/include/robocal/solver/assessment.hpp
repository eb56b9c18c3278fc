// One fit, assessed: the identification (calibrate.hpp) and everything an engineer needs to judge
// and use it: the parameter table with 1-sigma uncertainties, residuals per shell with the worst
// shells named, the predicted ball-position error, outliers, held-out samples predicted without
// refitting, the truth of a simulation, and the problems that make the fit unusable as a
// calibration (rank below the robot's independent parameters, a predicted error above the nominal
// model's).
//
// `robocal solve` and robocald's per-set fit both call assessFit and print fitSummaryJson
// (formats/report.hpp) of its result, so the daemon's RESULT equals `robocal solve --json` on the
// same samples by construction. Values are in interface units (mm, deg, gain); no I/O.
#pragma once

#include <robocal/kinematics/model.hpp>
#include <robocal/kinematics/sample.hpp>
#include <robocal/solver/adequacy.hpp>
#include <robocal/solver/calibrate.hpp>
#include <robocal/solver/compliance_fit.hpp>
#include <robocal/solver/verdict.hpp>

#include <optional>
#include <string>
#include <vector>

namespace robocal {

// Samples predicted by a model without refitting it: held-out data (robocal solve --validate), or
// a later shell set predicted by the earlier set's fit (robocald; the paper's validation).
struct HeldOutSamples {
  std::vector<Sample> samples;
  // The model that predicts them; when empty, the calibrated model of this fit.
  std::optional<Model> predictor;
  // What they are, for titles and reports: "set 2 predicted by the set-1 fit".
  std::string description;
};

struct AssessOptions {
  SolveOptions solve;
  double outlier_sigmas = 5.0;  // samples beyond this many robust sigmas are reported
  bool drop_outliers = false;   // and, when set, dropped before a second fit
  std::optional<HeldOutSamples> validation;
  TrueBallMm truth;       // a simulation's true robot: where it puts each sample's ball; or none
  VerdictLimits verdict;  // what makes the fit unusable (verdict.hpp)
  // Identify the gravity compliance of the loaded joints with the 54 parameters, from the
  // nominal's load (compliance_fit.hpp), when the nominal carries one: by default, since over the
  // arm's whole range a rigid fit leaves the twist its offsets and gains absorbed near the shells
  // (docs/accuracy.md). false: a rigid fit (robocal solve --rigid).
  bool identify_compliance = true;
};

// One of the 54 parameters, in interface units: mm, deg, or a unitless gain (paramName and
// paramUnit of `index` name it).
struct ParameterRow {
  int index = 0;  // into ParamVector
  double nominal = 0;
  double calibrated = 0;
  double sigma = 0;        // 1-sigma from the covariance; 0 when not estimated
  bool estimated = false;  // false: not identifiable from these data, fixed at nominal
  double change() const { return calibrated - nominal; }
};

// A shell whose residual RMS is at least this many times the median shell's stands out.
inline constexpr double kShellStandsOut = 2.0;
// How many of the worst shells the summaries name.
inline constexpr int kWorstShellsNamed = 3;

// The residuals of one shell (one shell number, connection and extension).
struct ShellResiduals {
  int shell = 0;
  Connection connection;
  double extension_mm = 0;
  ResidualStats stats;
  double rms_to_median = 0;  // this shell's RMS over the median of the shells' RMS
  bool stands_out = false;   // rms_to_median >= kShellStandsOut
};

struct ShellTable {
  std::vector<ShellResiduals> shells;  // by shell number
  std::vector<int> worst;              // indices into shells, worst RMS first, kWorstShellsNamed
};
ShellTable shellTable(const std::vector<Sample>& samples, const Eigen::VectorXd& residuals);

struct FlaggedOutlier {
  Sample sample;
  double residual_mm = 0;
  double robust_sigmas = 0;
};

struct ValidationResult {
  std::string description;  // HeldOutSamples::description
  std::vector<Sample> samples;
  Eigen::VectorXd residuals;
  ResidualStats stats;
  ShellTable shells;
};

struct FitAssessment {
  Model nominal;
  Model calibrated;  // the nominal's names, limits and fixtures with the fitted parameters
  std::vector<Sample> samples;  // those fitted (without the outliers when they were dropped)
  SolveResult fit;
  double outlier_sigmas = 0;
  std::vector<FlaggedOutlier> outliers;    // found in the first fit
  bool outliers_dropped = false;           // and dropped before the second
  double predicted_ball_error_rms_mm = 0;  // 1-sigma, over the fitted samples' poses
  double predicted_ball_error_max_mm = 0;
  double bar_to_endpoint_factor = 0;
  std::vector<ParameterRow> parameters;  // all 54, in chain order
  ShellTable shells;
  std::vector<Connection> connections;  // those in the fitted samples, in B1C1 ... B3C3 order
  // Why the calibrated model should not replace the nominal, one sentence each (what and why);
  // empty for a usable fit.
  std::vector<std::string> problems;
  // Whether the residual follows a pattern of error the model does not contain (adequacy.hpp).
  Adequacy adequacy;
  // The identified compliance (AssessOptions::identify_compliance), also in calibrated.compliance.
  std::optional<ComplianceEstimate> compliance;
  std::optional<ValidationResult> validation;
  std::optional<TruthComparison> truth;  // at the validation samples' poses, else the fitted ones
};

// Fits `samples` from `nominal` and assesses the fit. Throws std::invalid_argument as
// solveCalibration does (no samples, a ball or chuck that does not exist), and for held-out
// samples that name one.
FitAssessment assessFit(const Model& nominal, std::vector<Sample> samples,
                        const AssessOptions& options = {});

// The calibrated model's covariance: the 54's and the loaded joints' twists when the fit looked
// for a twist (kept or not: compliance_fit.hpp), else the 54's.
const Eigen::MatrixXd& calibratedCovariance(const FitAssessment& a);

}  // namespace robocal
