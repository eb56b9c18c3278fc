// The outputs of an accuracy assessment (accuracy.hpp), the same for `robocal accuracy`,
// `robocal solve --report` and robocald's RESULT: the statistics as JSON (keys name their units),
// as text for a terminal, and an SVG map of the error over the work volume.
#pragma once

#include <robocal/compensation/accuracy.hpp>

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace robocal {

// {"poses_from", "poses", "ok", "predicted_position_error_mm": {"rms", "p95", "max"},
//  "predicted_orientation_error_deg": {...}, and with a truth
//  "nominal_commanded_position_error_mm", "compensated_commanded_...", "calibrated_model_..."
//  (position and orientation)}; with
// `per_pose`, also "per_pose": one object per target (pose, status, joints, errors).
nlohmann::ordered_json accuracyJson(const AccuracyReport& report, bool per_pose = false);

// Lines for a terminal, each statistic with its unit.
std::string accuracyText(const AccuracyReport& report);

// The targets seen from above (x, y in the world frame), each a dot coloured by its error: the
// predicted error, and with a truth the true error commanded with the nominal and with the
// compensated readings, one panel each; the predicted and the compensated share a colour scale,
// the nominal (far larger) has its own.
std::string accuracySvg(const AccuracyReport& report);

// The predicted error over the work volume of a fit (no truth), as `robocal solve` and robocald
// add it to a fit's RESULT and report: the compensator's calibrated model over `work`.
// Throws std::invalid_argument when the volume is out of reach (workVolumePoses).
AccuracyReport predictedWorkVolumeAccuracy(const Compensator& compensator, const WorkVolume& work,
                                           const std::string& poses_from);

// The predicted error over the arm's whole range (wholeRangeJoints of the calibrated model), beside
// the work volume's.
AccuracyReport predictedWholeRangeAccuracy(const Compensator& compensator);

// A fit's predicted accuracy where the user works and beyond it, as `robocal solve` and robocald's
// RESULT report it, from the same code: JSON for the "work_volume" and "whole_range" keys
// ({"error": ...} when one cannot be computed: a volume out of reach, a model compensation cannot
// use), the text for a terminal, the work volume's and the whole range's RMS, and the work
// volume's report for writeWorkVolumeReport. No I/O.
struct PredictedAccuracy {
  nlohmann::ordered_json work_volume, whole_range;
  std::string text;
  std::optional<double> work_volume_rms_mm, whole_range_rms_mm;
  std::string problem;  // why one of them is missing, "" when both are there
  std::optional<AccuracyReport> work_volume_report;
};
PredictedAccuracy predictedAccuracy(const Model& nominal, const Model& calibrated,
                                    const WorkVolume& work);

// Writes DIR/work_volume.json (accuracyJson with every pose) and DIR/work_volume.svg; returns
// the SVG's text (the fit's summary page shows it).
std::string writeWorkVolumeReport(const std::string& dir, const AccuracyReport& report);

}  // namespace robocal
