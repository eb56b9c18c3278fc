// Inside formats: the pieces report.cpp and summary_html.cpp share. Not installed.
#pragma once

#include <robocal/formats/report.hpp>
#include <robocal/formats/result_verdict.hpp>
#include <robocal/solver/assessment.hpp>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace robocal::report_detail {

// Text made safe for XML and HTML: & < > " ' escaped.
std::string escapeXml(const std::string& text);

// printf of up to four numbers into a string.
std::string fmt(const char* format, double a, double b = 0, double c = 0, double d = 0);

// The residuals per shell as JSON: shell, connection, extension_mm, n, rms_mm, max_abs_mm,
// mean_mm, rms_to_median, stands_out (the fit's report and the health check's verdict).
nlohmann::ordered_json shellsJson(const ShellTable& table);

using Figure = ReportFigure;

// The one-page summary: the model's name and provenance, the verdict, the headline numbers, the
// per-shell and parameter tables, and the figures inline (each linked to its file).
std::string summaryHtml(const FitAssessment& fit, const Model& calibrated,
                        const ResultVerdict& verdict, const std::vector<Figure>& figures);

}  // namespace robocal::report_detail
