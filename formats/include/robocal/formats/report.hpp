// The fit report (robocal solve --report DIR): report.json with the summary and every figure's
// data, and the paper's Figures 3 and 4 as SVG files a person opens: residual against longitude
// (one series per shell) and the residual histogram with the fitted normal curve.
#pragma once

#include <robocal/kinematics/sample.hpp>
#include <robocal/solver/calibrate.hpp>

#include <nlohmann/json.hpp>

namespace robocal {

struct FitReport {
  const Model& nominal;
  const Model& calibrated;
  const std::vector<Sample>& samples;  // those fitted
  const SolveResult& fit;
  const std::vector<Outlier>& outliers;   // found in the first fit
  const std::vector<Sample>& dropped;     // outliers removed before the refit (may be empty)
  const std::vector<Sample>& validation;  // held-out samples (may be empty)
  const Eigen::VectorXd& validation_residuals;
  double ball_error_rms_mm;
  double ball_error_max_mm;
  double bar_to_endpoint_factor;
  TruthComparison truth;  // poses == 0 when no truth was given
  double outlier_sigmas;
};

// The summary robocal solve --json prints: rms_mm, rms_before_mm, n, rank, iterations, ... and
// validation_rms_mm when there is validation data.
nlohmann::ordered_json fitSummaryJson(const FitReport& report);

// Writes DIR/report.json, DIR/residuals_vs_longitude.svg, DIR/residual_histogram.svg and, with
// validation data, DIR/validation_vs_longitude.svg and DIR/validation_histogram.svg.
void writeReport(const std::string& dir, const FitReport& report);

}  // namespace robocal
