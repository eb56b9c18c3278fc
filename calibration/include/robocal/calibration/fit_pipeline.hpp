// One fit pipeline for robocal solve and robocald alike (docs/calibration.md, "One fit, every
// output"): from samples to the assessment (solver/assessment.hpp), the calibrated model with its
// provenance, the predicted accuracy where the user works and over the arm's whole range, the
// verdict (formats/result_verdict.hpp), the report folder, and the RESULT summary JSON.
//
// The steps stay separate because their callers store the model differently (robocal solve
// writes it only when usable or told to; robocald keeps every fit as a version) and the verdict's
// next step depends on where the model went; what each step computes is written once, here.
//   FitOutcome o = fitCalibration(...);          // math only, no I/O
//   ... store o.calibrated, then set o.verdict.model_file and the next step (nextStep*)
//   writeFitReport(o, dir);                      // the report folder, verdict included
//   fitResultJson(o);                            // RESULT / solve --json
#pragma once

#include <robocal/compensation/accuracy_report.hpp>
#include <robocal/formats/report.hpp>
#include <robocal/formats/result_verdict.hpp>
#include <robocal/kinematics/model.hpp>
#include <robocal/kinematics/sample.hpp>
#include <robocal/planner/cell.hpp>
#include <robocal/solver/assessment.hpp>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace robocal {

struct FitOutcome {
  FitAssessment fit;
  Model calibrated;  // named and with its provenance (calibratedModel)
  PredictedAccuracy accuracy;
  // Usable or not, why, the rank and the predicted accuracy; the caller sets model_file and the
  // next step once it has stored the model.
  ResultVerdict verdict;
};

// Fits and assesses `samples` from `nominal`, and predicts the calibrated model's accuracy over
// `work` and the arm's whole range. Throws as assessFit does.
FitOutcome fitCalibration(const Model& nominal, std::vector<Sample> samples,
                          const AssessOptions& options, const FitOrigin& origin,
                          const WorkVolume& work);

// The next step of a fit done offline (robocal solve): compensate with the written model; write
// it when it was not; or, when not usable, put the first problem right and fit again.
// `nominal_file` and the samples files (the origin's) make the command runnable as printed.
void nextStepOffline(ResultVerdict& verdict, const std::string& nominal_file,
                     const std::vector<std::string>& samples_files);
// The next step of a fit robocald stored as `model_version`: activate it (compensate requests
// use the active model) or, when not usable, put the first problem right and run again.
void nextStepDaemon(ResultVerdict& verdict, int model_version);

// Writes the report folder (writeReport) with the verdict and the work-volume map
// (work_volume.json, work_volume.svg) shown and linked in summary.html.
void writeFitReport(const FitOutcome& outcome, const std::string& dir);

// fitSummaryJson with "work_volume", "whole_range" and "verdict": what robocal solve --json
// prints and robocald's RESULT carries (with the daemon's run keys added).
nlohmann::ordered_json fitResultJson(const FitOutcome& outcome);

}  // namespace robocal
