// The outputs of a fit (solver/assessment.hpp), the same for robocal solve and robocald:
// - fitSummaryJson: the object `robocal solve --json` prints and robocald's RESULT carries (with
//   the daemon's run keys added): the headline numbers, the parameter table, the shells, the
//   problems;
// - calibratedModel: the calibrated model as written, named "<nominal> calibrated <date>" with its
//   provenance (docs/model-format.md);
// - writeReport: DIR/report.json (the summary and every figure's data), the paper's Figures 3 and 4
//   as SVG (residual against longitude, one series per shell; the residual histogram with its
//   fitted normal curve), the residual RMS per shell, the same for the held-out samples, and
//   DIR/summary.html, one self-contained page with the numbers, tables and figures.
// Units: mm and deg, named in every key (gains are unitless: "gain").
#pragma once

#include <robocal/formats/result_verdict.hpp>
#include <robocal/kinematics/sample.hpp>
#include <robocal/solver/assessment.hpp>

#include <chrono>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace robocal {

// "mm", "deg" or "gain": the unit of parameter `index` in tables and key names.
const char* paramUnitLabel(int index);
// A parameter value in its unit with the table's precision: 4 decimals in mm, 5 in deg, 6 for a
// gain; `sign` writes + for positive values (changes).
std::string formatParamValue(int index, double value, bool sign = false);

// "B1C2" and "B1C2 +150 mm" for a shell with an extension.
std::string shellConnectionText(const ShellResiduals& shell);

// The version of robocal recorded in what it writes.
const char* robocalVersion();

// Where a fit's data came from, for the calibrated model's provenance.
struct FitOrigin {
  std::string run_id;  // the robocald run, "" for robocal solve
  std::vector<std::string> samples_files;
  double approach_deg = 0;  // the plan's motion.approach_deg (ModelProvenance::approach_deg)
};

// The model to write: the fitted parameters named "<nominal name> calibrated <YYYY-MM-DD>" (UTC)
// with a provenance: run, date, samples files and count, RMS, rank, version, and the fit's
// problems as warnings.
Model calibratedModel(
    const FitAssessment& fit, const FitOrigin& origin,
    std::chrono::system_clock::time_point made = std::chrono::system_clock::now());

// The summary: class "RESULT", n, rank, expected_rank, problems, rms_before_mm, rms_mm, ...,
// parameter_table, shells, worst_shells, and validation_* and truth_* when there are such data
// (docs/calibration.md lists every key).
nlohmann::ordered_json fitSummaryJson(const FitAssessment& fit);

// A figure in the report folder: its file name there, a caption, and its SVG text.
struct ReportFigure {
  std::string file;
  std::string caption;
  std::string svg;
};

// What the report holds beyond the fit itself: the verdict (with the predicted accuracy, the
// model's path and the next step; without one, the page's box says usable or not from the fit
// alone) and figures others wrote into the folder (the work-volume map), shown and linked.
struct ReportExtras {
  std::optional<ResultVerdict> verdict;
  std::vector<ReportFigure> figures;
};

// The verdict from the fit alone: usable or not, why, and the rank; no accuracy, model or next
// step.
ResultVerdict fitOnlyVerdict(const FitAssessment& fit);

// Writes DIR/report.json, DIR/summary.html, DIR/residuals_vs_longitude.svg,
// DIR/residual_histogram.svg, DIR/shell_rms.svg and, with held-out samples, DIR/validation_*.svg.
// `calibrated` is the model as written (its name and provenance head the summary page).
void writeReport(const std::string& dir, const FitAssessment& fit, const Model& calibrated,
                 const ReportExtras& extras = {});

}  // namespace robocal
