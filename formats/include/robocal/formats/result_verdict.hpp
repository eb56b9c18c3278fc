// The verdict on one calibration, as every output gives it: summary.html's box, robocal solve's
// last lines, robocald's RESULT ("verdict") and `robocal result`, the console's result card and
// the main job's last block. Usable or not and why, the predicted position error where the user
// works and beyond it, where the model is, and the command to run next. One struct, one JSON
// object, one text and one HTML rendering, so that no two outputs can say different things.
// Pure: no I/O.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace robocal {

struct ResultVerdict {
  bool usable = false;
  std::vector<std::string> problems;  // why not (fitProblems), the likeliest cause first
  int rank = 0;
  int expected_rank = 0;
  // Predicted 1-sigma tool position error (RMS) over the cell's work volume and over the arm's
  // whole range; absent when it could not be computed (`accuracy_note` says why).
  std::optional<double> work_volume_rms_mm;
  std::optional<double> whole_range_rms_mm;
  std::string accuracy_note;
  std::string model_file;  // the calibrated model as written; "" when none was written
  std::string next_command;
  std::string next_why;  // one sentence: what the command is for
};

// {"class": "VERDICT", "usable", "problems", "rank", "expected_rank",
//  "predicted_position_error_mm": {"work_volume_rms", "whole_range_rms"} (null when unknown),
//  "accuracy_note", "model_file" (null when none), "next": {"command", "why"}}.
nlohmann::ordered_json resultVerdictJson(const ResultVerdict& verdict);
// The inverse, for clients (robocal result); a missing key reads as its default.
ResultVerdict resultVerdictFromJson(const nlohmann::json& j);

// A few lines for a terminal, the first "verdict: usable ..." or "verdict: NOT USABLE ...".
std::string resultVerdictText(const ResultVerdict& verdict);
// The box at the top of summary.html (escaped; classes 'verdict ok' or 'verdict bad').
std::string resultVerdictHtml(const ResultVerdict& verdict);

}  // namespace robocal
