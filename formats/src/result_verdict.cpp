#include <robocal/formats/result_verdict.hpp>

#include "report_parts.hpp"

namespace robocal {
namespace {

using ojson = nlohmann::ordered_json;

ojson optionalMm(const std::optional<double>& v) {
  return v ? ojson(*v) : ojson();
}

std::optional<double> optionalNumber(const nlohmann::json& j, const char* key) {
  if (!j.contains(key) || !j[key].is_number()) return std::nullopt;
  return j[key].get<double>();
}

std::string mmText(const std::optional<double>& v) {
  return v ? report_detail::fmt("%.3f mm RMS", *v) : std::string("not computed");
}

std::string headline(const ResultVerdict& v) {
  return std::string(v.usable ? "usable as a calibration" : "NOT USABLE as a calibration") +
         " (rank " + std::to_string(v.rank) + " of " + std::to_string(v.expected_rank) + ")";
}

std::string accuracyLine(const ResultVerdict& v) {
  std::string line = "predicted position error: " + mmText(v.work_volume_rms_mm) +
                     " in the work volume, " + mmText(v.whole_range_rms_mm) +
                     " over the arm's whole range";
  if (!v.accuracy_note.empty()) line += " (" + v.accuracy_note + ")";
  return line;
}

std::string modelLine(const ResultVerdict& v) {
  if (v.model_file.empty()) return "model: none written";
  return "model: " + v.model_file + (v.usable ? "" : " (written with its problems as warnings)");
}

}  // namespace

ojson resultVerdictJson(const ResultVerdict& v) {
  return {{"class", "VERDICT"},
          {"usable", v.usable},
          {"problems", v.problems},
          {"rank", v.rank},
          {"expected_rank", v.expected_rank},
          {"predicted_position_error_mm",
           {{"work_volume_rms", optionalMm(v.work_volume_rms_mm)},
            {"whole_range_rms", optionalMm(v.whole_range_rms_mm)}}},
          {"accuracy_note", v.accuracy_note},
          {"model_file", v.model_file.empty() ? ojson() : ojson(v.model_file)},
          {"next", {{"command", v.next_command}, {"why", v.next_why}}}};
}

ResultVerdict resultVerdictFromJson(const nlohmann::json& j) {
  ResultVerdict v;
  if (!j.is_object()) return v;
  v.usable = j.value("usable", false);
  if (j.contains("problems") && j["problems"].is_array())
    for (const auto& p : j["problems"])
      if (p.is_string()) v.problems.push_back(p.get<std::string>());
  v.rank = j.value("rank", 0);
  v.expected_rank = j.value("expected_rank", 0);
  if (j.contains("predicted_position_error_mm") && j["predicted_position_error_mm"].is_object()) {
    const auto& e = j["predicted_position_error_mm"];
    v.work_volume_rms_mm = optionalNumber(e, "work_volume_rms");
    v.whole_range_rms_mm = optionalNumber(e, "whole_range_rms");
  }
  v.accuracy_note = j.value("accuracy_note", "");
  if (j.contains("model_file") && j["model_file"].is_string())
    v.model_file = j["model_file"].get<std::string>();
  if (j.contains("next") && j["next"].is_object()) {
    v.next_command = j["next"].value("command", "");
    v.next_why = j["next"].value("why", "");
  }
  return v;
}

std::string resultVerdictText(const ResultVerdict& v) {
  std::string out = "verdict: " + headline(v) + (v.problems.empty() ? "\n" : ":\n");
  for (const std::string& p : v.problems) out += "  - " + p + "\n";
  out += "  " + accuracyLine(v) + "\n";
  out += "  " + modelLine(v) + "\n";
  if (!v.next_command.empty()) {
    out += "  next: " + v.next_command + "\n";
    if (!v.next_why.empty()) out += "        " + v.next_why + "\n";
  }
  return out;
}

std::string resultVerdictHtml(const ResultVerdict& v) {
  using report_detail::escapeXml;
  std::string h = std::string("<div class='verdict ") + (v.usable ? "ok" : "bad") +
                  "' id='verdict'><b>" + escapeXml(headline(v)) + "</b>";
  if (!v.problems.empty()) {
    h += "<ul>";
    for (const std::string& p : v.problems) h += "<li>" + escapeXml(p) + "</li>";
    h += "</ul>";
  }
  h += "<p>" + escapeXml(accuracyLine(v)) + "<br>" + escapeXml(modelLine(v)) + "</p>";
  if (!v.next_command.empty())
    h += "<p>Next: <code>" + escapeXml(v.next_command) + "</code>" +
         (v.next_why.empty() ? "" : "<br>" + escapeXml(v.next_why)) + "</p>";
  return h + "</div>\n";
}

}  // namespace robocal
