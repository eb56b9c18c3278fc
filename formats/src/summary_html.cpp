// summary.html: one page per fit, self-contained (inline CSS, the report's SVG figures inline and
// linked to their files), for an engineer to read and to pass on.
#include <robocal/formats/report.hpp>

#include "report_parts.hpp"

namespace robocal::report_detail {
namespace {

constexpr const char* kStyle = R"(
body { font-family: sans-serif; margin: 24px auto; max-width: 1100px; color: #222; }
h1 { font-size: 22px; margin-bottom: 4px; }
h2 { font-size: 17px; margin-top: 28px; border-bottom: 1px solid #ccc; }
.sub { color: #555; margin-top: 0; }
.verdict { padding: 10px 14px; border-radius: 4px; margin: 14px 0; }
.ok { background: #e5f5e0; border: 1px solid #74c476; }
.bad { background: #fee0d2; border: 1px solid #de2d26; }
.verdict p { margin: 6px 0 0; }
.verdict code { font-size: 13px; background: #fff8; padding: 1px 4px; }
p { font-size: 14px; }
table { border-collapse: collapse; font-size: 13px; }
td, th { padding: 3px 10px; border-bottom: 1px solid #e5e5e5; text-align: right; }
th { background: #f3f3f3; }
td.l, th.l { text-align: left; }
tr.out td { background: #fee0d2; }
tr.fixed td { color: #999; }
.headline td:first-child { text-align: left; color: #555; }
.cols { display: flex; gap: 40px; flex-wrap: wrap; align-items: flex-start; }
figure { margin: 18px 0; }
figure svg { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { font-size: 13px; color: #555; }
)";

std::string e(const std::string& text) {
  return escapeXml(text);
}

std::string mm(double v, const char* format = "%.4f") {
  return fmt(format, v) + " mm";
}

std::string row(const std::string& label, const std::string& value) {
  return "<tr><td>" + e(label) + "</td><td class='l'>" + e(value) + "</td></tr>\n";
}

std::string shellTableHtml(const ShellTable& table) {
  std::string out =
      "<table><tr><th>shell</th><th class='l'>connection</th><th>n</th><th>RMS (mm)</th>"
      "<th>max |r| (mm)</th><th>mean (mm)</th><th>RMS / median</th></tr>\n";
  for (const ShellResiduals& s : table.shells)
    out += std::string(s.stands_out ? "<tr class='out'>" : "<tr>") + "<td>" +
           std::to_string(s.shell) + "</td><td class='l'>" + e(shellConnectionText(s)) +
           "</td><td>" + std::to_string(s.stats.count) + "</td><td>" + fmt("%.4f", s.stats.rms_mm) +
           "</td><td>" + fmt("%.4f", s.stats.max_abs_mm) + "</td><td>" +
           fmt("%+.4f", s.stats.mean_mm) + "</td><td>" + fmt("%.2f", s.rms_to_median) +
           "</td></tr>\n";
  out += "</table>\n<p>Worst shells: ";
  for (size_t k = 0; k < table.worst.size(); ++k) {
    const ShellResiduals& s = table.shells[table.worst[k]];
    out += (k ? ", " : "") + std::to_string(s.shell) + " " + e(shellConnectionText(s)) + " (" +
           mm(s.stats.rms_mm) + fmt(", %.1fx the median", s.rms_to_median) + ")";
  }
  out += fmt(". Red rows: RMS at least %gx the median shell's.</p>\n", kShellStandsOut);
  return out;
}

std::string parameterTableHtml(const std::vector<ParameterRow>& rows) {
  std::string out =
      "<table><tr><th class='l'>parameter</th><th class='l'>unit</th><th>nominal</th>"
      "<th>calibrated</th><th>change</th><th>1-sigma</th><th class='l'>status</th></tr>\n";
  for (const ParameterRow& p : rows)
    out += std::string(p.estimated ? "<tr>" : "<tr class='fixed'>") + "<td class='l'>" +
           paramName(p.index) + "</td><td class='l'>" + paramUnitLabel(p.index) + "</td><td>" +
           formatParamValue(p.index, p.nominal) + "</td><td>" +
           formatParamValue(p.index, p.calibrated) + "</td><td>" +
           formatParamValue(p.index, p.change(), true) + "</td><td>" +
           (p.estimated ? formatParamValue(p.index, p.sigma) : std::string()) +
           "</td><td class='l'>" + (p.estimated ? "estimated" : "fixed at nominal") +
           "</td></tr>\n";
  out += "</table>\n";
  return out;
}

}  // namespace

std::string summaryHtml(const FitAssessment& a, const Model& calibrated,
                        const ResultVerdict& verdict, const std::vector<Figure>& figures) {
  const SolveResult& fit = a.fit;
  std::string h = "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>\n<title>" +
                  e(calibrated.name) + "</title>\n<style>" + kStyle + "</style></head><body>\n";
  h += "<h1>" + e(calibrated.name) + "</h1>\n";
  std::string sub = "fitted from " + (a.nominal.name.empty() ? "the nominal" : a.nominal.name);
  if (calibrated.provenance) {
    const ModelProvenance& p = *calibrated.provenance;
    sub += " on " + p.date_utc + (p.run_id.empty() ? "" : ", run " + p.run_id) + ", robocal " +
           p.robocal_version;
  }
  h += "<p class='sub'>" + e(sub) + "</p>\n";

  h += resultVerdictHtml(verdict);
  std::string standing_out;
  for (const ShellResiduals& s : a.shells.shells)
    if (s.stands_out)
      standing_out += (standing_out.empty() ? "" : ", ") + std::to_string(s.shell) + " " +
                      shellConnectionText(s) + fmt(" (%.1fx)", s.rms_to_median);
  if (!standing_out.empty())
    h += "<div class='verdict bad'>Check the set-up of shell(s) " + e(standing_out) +
         fmt(": residual RMS at least %gx the median shell's.</div>\n", kShellStandsOut);

  h += "<div class='cols'><div><h2>Headline</h2><table class='headline'>\n";
  h += row("samples fitted",
           std::to_string(a.samples.size()) + " on " + connectionList(a.connections));
  h += row("rank", std::to_string(fit.identifiability.rank) + " of " + std::to_string(kParamCount) +
                       " (expected " + std::to_string(fit.identifiability.expected) + ")");
  h += row("RMS residual", mm(fit.before.rms_mm) + " before, " + mm(fit.after.rms_mm) + " after");
  h += row("max |residual|", mm(fit.after.max_abs_mm));
  h += row("sigma", mm(fit.sigma_mm));
  h += row(
      "predicted ball-position error (1-sigma)",
      "RMS " + mm(a.predicted_ball_error_rms_mm) + ", max " + mm(a.predicted_ball_error_max_mm));
  h += row("bar-to-endpoint error factor", fmt("%.2f", a.bar_to_endpoint_factor));
  h += row("condition number, O1, O3",
           fmt("%.4g, %.4g, %.4g", fit.condition_number, fit.o1, fit.o3));
  h += row("iterations", std::to_string(fit.iterations) + " (" + stopReasonText(fit.stop) + ")");
  h += row("outliers beyond " + fmt("%.1f", a.outlier_sigmas) + " robust sigmas",
           std::to_string(a.outliers.size()) + (a.outliers_dropped ? " (dropped, refitted)" : ""));
  if (a.validation)
    h += row(a.validation->description, std::to_string(a.validation->stats.count) +
                                            " samples, RMS " + mm(a.validation->stats.rms_mm) +
                                            ", max " + mm(a.validation->stats.max_abs_mm));
  // The evidence robocal solve prints beside the verdict: what the model may not contain, the
  // bar's own noise (from revisits), the drift, the twist, how the points were reached.
  h += row("model adequacy", a.adequacy.summary());
  if (a.adequacy.drift.places > 0) h += row("drift", a.adequacy.drift.summary());
  if (a.compliance) h += row("gravity compliance", a.compliance->summary());
  if (calibrated.provenance)
    h += row("approach", calibrated.provenance->approach_deg > 0
                             ? fmt("every point up from a pre-point %.4g deg below it in every "
                                   "joint: compensate reaches targets so too",
                                   calibrated.provenance->approach_deg)
                             : std::string("none: the points were reached as the paths came, "
                                           "targets are reached from either side, and the "
                                           "predicted errors count each joint's backlash"));
  if (a.truth)
    h += row("ball-position error against the truth",
             "nominal RMS " + mm(a.truth->nominal_rms_mm) + ", calibrated RMS " +
                 mm(a.truth->calibrated_rms_mm) + " (max " + mm(a.truth->calibrated_max_mm) + ")");
  h += "</table></div>\n";
  if (calibrated.provenance) {
    const ModelProvenance& p = *calibrated.provenance;
    h += "<div><h2>Provenance</h2><table class='headline'>\n";
    h += row("date (UTC)", p.date_utc);
    if (!p.run_id.empty()) h += row("run", p.run_id);
    for (const std::string& f : p.samples_files) h += row("samples file", f);
    h += row("robocal", p.robocal_version);
    h += "</table></div>\n";
  }
  h += "</div>\n";

  h += "<h2>Residual per shell (after the fit)</h2>\n" + shellTableHtml(a.shells);
  if (a.validation)
    h += "<h2>Residual per shell: " + e(a.validation->description) + "</h2>\n" +
         shellTableHtml(a.validation->shells);
  h += "<h2>Figures</h2>\n";
  for (const Figure& f : figures)
    h += "<figure>" + f.svg + "<figcaption><a href='" + e(f.file) + "'>" + e(f.file) +
         "</a>: " + e(f.caption) + "</figcaption></figure>\n";
  h += "<h2>Parameters</h2>\n<p>" + std::to_string(fit.free_params.size()) +
       " estimated; the others are not identifiable from these data and stay at their nominal "
       "values. 1-sigma from the covariance sigma<sup>2</sup> (J<sup>T</sup>J)<sup>-1</sup> of "
       "the estimated parameters. Gains are unitless.</p>\n" +
       parameterTableHtml(a.parameters);
  h += "<p class='sub'>report.json holds these numbers and every figure's data.</p>\n";
  h += "</body></html>\n";
  return h;
}

}  // namespace robocal::report_detail
