#include <robocal/formats/report.hpp>

#include <robocal/build_info.hpp>
#include <robocal/formats/error.hpp>

#include "report_parts.hpp"
#include "svg_chart.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <map>
#include <numbers>

namespace robocal {
namespace report_detail {

std::string escapeXml(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string fmt(const char* format, double a, double b, double c, double d) {
  char buf[256];
  std::snprintf(buf, sizeof buf, format, a, b, c, d);
  return buf;
}

nlohmann::ordered_json shellsJson(const ShellTable& table) {
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  for (const ShellResiduals& s : table.shells)
    out.push_back({{"shell", s.shell},
                   {"connection", connectionName(s.connection)},
                   {"extension_mm", s.extension_mm},
                   {"n", s.stats.count},
                   {"rms_mm", s.stats.rms_mm},
                   {"max_abs_mm", s.stats.max_abs_mm},
                   {"mean_mm", s.stats.mean_mm},
                   {"rms_to_median", s.rms_to_median},
                   {"stands_out", s.stands_out}});
  return out;
}

}  // namespace report_detail

namespace {

using ojson = nlohmann::ordered_json;
using report_detail::ChartAxis;
using report_detail::escapeXml;
using report_detail::Figure;
using report_detail::fmt;
using report_detail::Marker;
using report_detail::shellsJson;
using report_detail::SvgChart;

// The drift of the places measured more than once (null figures when not measured).
ojson driftJson(const Drift& d) {
  const auto measured = [&](double v) { return d.measured ? ojson(v) : ojson(nullptr); };
  return {{"measured", d.measured},
          {"found", d.found},
          {"significant", d.significant},
          {"places", d.places},
          {"readings", d.readings},
          {"span_min", d.span_min},
          {"rate_mm_per_h", measured(d.rate_mm_per_h)},
          {"rate_sigma_mm_per_h", measured(d.rate_sigma_mm_per_h)},
          {"over_span_mm", measured(d.over_span_mm)},
          {"limit_mm", d.limit_mm},
          {"summary", d.summary()}};
}

double symmetricLimit(const Eigen::VectorXd& r) {
  const double m = r.size() ? r.cwiseAbs().maxCoeff() : 1.0;
  return m > 0 ? m * 1.1 : 1.0;
}

std::string sampleConnectionText(const Sample& s) {
  return connectionName({s.ball_index, s.chuck_index}) +
         (s.extension_mm > 0 ? fmt(" +%.0f mm", s.extension_mm) : "");
}

// Figure 3: residual against longitude, one series per shell: one colour per connection, one
// marker per bar extension.
ojson longitudeFigure(const std::vector<Sample>& samples, const Eigen::VectorXd& r,
                      const std::string& title, std::string* svg) {
  const double lim = symmetricLimit(r);
  SvgChart chart(title, ChartAxis{"longitude (deg)", 0, 360, 45},
                 ChartAxis{"residual (mm)", -lim, lim});
  std::map<int, ojson> series;
  std::map<int, std::string> names;
  std::map<int, std::pair<std::string, double>> shell_looks;  // connection, extension
  std::map<std::string, size_t> colours;
  std::map<double, size_t> markers;
  for (size_t i = 0; i < samples.size(); ++i) {
    const Sample& s = samples[i];
    ojson& shell = series[s.shell];
    if (shell.is_null()) shell = {{"lon_deg", ojson::array()}, {"residual_mm", ojson::array()}};
    shell["lon_deg"].push_back(s.lon_deg);
    shell["residual_mm"].push_back(r[static_cast<Eigen::Index>(i)]);
    names[s.shell] = sampleConnectionText(s);
    shell_looks[s.shell] = {connectionName({s.ball_index, s.chuck_index}), s.extension_mm};
    markers.emplace(s.extension_mm, 0);
  }
  for (const auto& [shell, look] : shell_looks) colours.emplace(look.first, colours.size());
  size_t k = 0;
  for (auto& [extension, index] : markers) index = k++;
  ojson out = {{"x", "lon_deg"}, {"y", "residual_mm"}, {"series", ojson::array()}};
  int row = 0;
  for (const auto& [shell, data] : series) {
    const auto& [connection, extension] = shell_looks[shell];
    const std::string& colour = report_detail::paletteColour(colours[connection]);
    const Marker shape = report_detail::markerFor(markers[extension]);
    for (size_t j = 0; j < data["lon_deg"].size(); ++j)
      chart.marker(std::fmod(data["lon_deg"][j].get<double>() + 360.0, 360.0),
                   data["residual_mm"][j].get<double>(), colour, shape);
    chart.legend(row++, "shell " + std::to_string(shell) + " " + names[shell], colour, shape);
    out["series"].push_back({{"shell", shell},
                             {"connection", names[shell]},
                             {"lon_deg", data["lon_deg"]},
                             {"residual_mm", data["residual_mm"]}});
  }
  *svg = chart.svg();
  return out;
}

// Figure 4: histogram of the residuals with the normal curve of their mean and sigma.
ojson histogramFigure(const Eigen::VectorXd& r, const std::string& title, std::string* svg) {
  const double n = static_cast<double>(r.size());
  const double mean = r.mean();
  const double sigma = std::sqrt((r.array() - mean).square().sum() / std::max(1.0, n - 1));
  const double lim = std::max(symmetricLimit(r), 4 * sigma);
  const int bins = std::clamp(static_cast<int>(std::sqrt(n)), 8, 40);
  const double width = 2 * lim / bins;
  std::vector<int> counts(bins, 0);
  for (Eigen::Index i = 0; i < r.size(); ++i)
    ++counts[std::clamp(static_cast<int>((r[i] + lim) / width), 0, bins - 1)];
  const double peak_normal = n * width / (sigma * std::sqrt(2 * std::numbers::pi));
  const double top = 1.15 * std::max<double>(*std::max_element(counts.begin(), counts.end()),
                                             std::isfinite(peak_normal) ? peak_normal : 0);
  SvgChart chart(title, ChartAxis{"residual (mm)", -lim, lim},
                 ChartAxis{"samples per bin (count)", 0, top, 0, 1});
  ojson bin_json = ojson::array();
  for (int b = 0; b < bins; ++b) {
    chart.bar(-lim + b * width, -lim + (b + 1) * width, counts[b]);
    bin_json.push_back(
        {{"from_mm", -lim + b * width}, {"to_mm", -lim + (b + 1) * width}, {"count", counts[b]}});
  }
  std::vector<std::pair<double, double>> curve;
  if (sigma > 0)
    for (int k = 0; k <= 200; ++k) {
      const double x = -lim + 2 * lim * k / 200;
      curve.emplace_back(x, peak_normal * std::exp(-0.5 * std::pow((x - mean) / sigma, 2)));
    }
  chart.polyline(curve, "#d62728");
  chart.note(0, fmt("n = %.0f   mean = %.4f mm   sigma = %.4f mm", n, mean, sigma));
  *svg = chart.svg();
  return {{"mean_mm", mean}, {"sigma_mm", sigma}, {"n", r.size()}, {"bins", bin_json}};
}

// Residual RMS per shell as bars (stand-outs in red) with each shell's max |residual| as a dot,
// and the median shell's RMS and the stand-out level as dashed lines.
ojson shellFigure(const ShellTable& table, const std::string& title, std::string* svg) {
  const auto& shells = table.shells;
  double top = 0, median_rms = 0;
  for (const ShellResiduals& s : shells) {
    top = std::max(top, s.stats.max_abs_mm);
    if (s.rms_to_median > 0) median_rms = s.stats.rms_mm / s.rms_to_median;
  }
  top = std::max({top, kShellStandsOut * median_rms, 1e-6}) * 1.1;
  const double count = static_cast<double>(std::max<size_t>(shells.size(), 1));
  SvgChart chart(title,
                 ChartAxis{"shell, connection, bar extension (mm)", -0.5, count - 0.5, 0, 0, false},
                 ChartAxis{"residual (mm)", 0, top});
  ojson out = ojson::array();
  for (size_t k = 0; k < shells.size(); ++k) {
    const ShellResiduals& s = shells[k];
    const double x = static_cast<double>(k);
    chart.bar(x - 0.35, x + 0.35, s.stats.rms_mm, s.stands_out ? "#fc9272" : "#9ecae1",
              s.stands_out ? "#de2d26" : "#3182bd");
    chart.dot(x, s.stats.max_abs_mm, "#252525", 3);
    chart.xLabel(x, 0, std::to_string(s.shell));
    chart.xLabel(x, 1, connectionName(s.connection));
    if (s.extension_mm > 0) chart.xLabel(x, 2, fmt("+%.0f", s.extension_mm));
    out.push_back(
        {{"shell", s.shell}, {"rms_mm", s.stats.rms_mm}, {"max_abs_mm", s.stats.max_abs_mm}});
  }
  if (median_rms > 0) {
    chart.level(median_rms, "#636363", "median RMS");
    chart.level(kShellStandsOut * median_rms, "#de2d26", fmt("%gx median", kShellStandsOut));
  }
  chart.legend(4, "bar: RMS", "#3182bd");
  chart.legend(5, "dot: max |residual|", "#252525");
  chart.legend(6, "red: stands out", "#de2d26");
  *svg = chart.svg();
  return {{"x", "shell"}, {"shells", out}};
}

ojson names(const std::vector<int>& indices) {
  ojson out = ojson::array();
  for (int i : indices) out.push_back(paramName(i));
  return out;
}

ojson sampleRef(const Sample& s) {
  return {{"file", s.source}, {"line", s.source_line}, {"shell", s.shell}};
}

ojson worstJson(const ShellTable& table) {
  ojson out = ojson::array();
  for (int k : table.worst) out.push_back(table.shells[k].shell);
  return out;
}

ojson parameterTableJson(const std::vector<ParameterRow>& rows) {
  ojson out = ojson::array();
  for (const ParameterRow& p : rows) {
    const std::string unit = paramUnitLabel(p.index);
    ojson row = {{"name", paramName(p.index)}, {"unit", unit}, {"estimated", p.estimated}};
    row["nominal_" + unit] = p.nominal;
    row["calibrated_" + unit] = p.calibrated;
    row["change_" + unit] = p.change();
    row["sigma_" + unit] = p.estimated ? ojson(p.sigma) : ojson(nullptr);
    out.push_back(row);
  }
  return out;
}

std::string dateUtc(std::chrono::system_clock::time_point t, const char* format) {
  const std::time_t seconds = std::chrono::system_clock::to_time_t(t);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, format, &tm);
  return buf;
}

}  // namespace

const char* paramUnitLabel(int index) {
  return paramKind(index) == ParamKind::kGain ? "gain" : paramUnit(index);
}

std::string formatParamValue(int index, double value, bool sign) {
  const ParamKind kind = paramKind(index);
  const char* format = kind == ParamKind::kTranslation ? (sign ? "%+.4f" : "%.4f")
                       : kind == ParamKind::kAngle     ? (sign ? "%+.5f" : "%.5f")
                                                       : (sign ? "%+.6f" : "%.6f");
  return fmt(format, value);
}

std::string shellConnectionText(const ShellResiduals& shell) {
  return connectionName(shell.connection) +
         (shell.extension_mm > 0 ? fmt(" +%.0f mm", shell.extension_mm) : "");
}

const char* robocalVersion() {
  return build::kVersion;
}

Model calibratedModel(const FitAssessment& fit, const FitOrigin& origin,
                      std::chrono::system_clock::time_point made) {
  Model m = fit.calibrated;
  const std::string day = dateUtc(made, "%Y-%m-%d");
  m.name =
      (fit.nominal.name.empty() ? std::string("model") : fit.nominal.name) + " calibrated " + day;
  ModelProvenance p;
  p.run_id = origin.run_id;
  p.date_utc = dateUtc(made, "%Y-%m-%dT%H:%M:%SZ");
  p.nominal_name = fit.nominal.name;
  p.nominal_params = toParams(fit.nominal);
  if (!fit.samples.empty()) {
    std::array<std::array<double, 2>, kJointCount> ranges;
    for (int j = 0; j < kJointCount; ++j) ranges[j] = {1e300, -1e300};
    for (const Sample& s : fit.samples)
      for (int j = 0; j < kJointCount; ++j) {
        ranges[j][0] = std::min(ranges[j][0], s.joints_deg[j]);
        ranges[j][1] = std::max(ranges[j][1], s.joints_deg[j]);
      }
    p.measured_joints_deg = ranges;
  }
  p.samples_files = origin.samples_files;
  p.approach_deg = origin.approach_deg;
  p.unmodelled_mm = fit.adequacy.unmodelled_bar_mm();
  p.samples = fit.samples.size();
  p.rms_mm = fit.fit.after.rms_mm;
  p.rank = fit.fit.identifiability.rank;
  p.expected_rank = fit.fit.identifiability.expected;
  p.robocal_version = robocalVersion();
  p.warnings = fit.problems;
  m.provenance = std::move(p);
  // What compensate's predicted errors come from: with the twist's when the fit looked for one.
  m.covariance = calibratedCovariance(fit);
  return m;
}

nlohmann::ordered_json fitSummaryJson(const FitAssessment& a) {
  const SolveResult& fit = a.fit;
  ojson problems = ojson::array();
  for (const std::string& p : a.problems) problems.push_back(p);
  ojson connections = ojson::array();
  for (const Connection& c : a.connections) connections.push_back(connectionName(c));
  ojson out = {{"class", "RESULT"},
               {"n", fit.after.count},
               {"rank", fit.identifiability.rank},
               {"expected_rank", fit.identifiability.expected},
               {"parameters", kParamCount},
               {"problems", problems},
               {"connections", connections},
               {"redundant", names(fit.identifiability.redundant)},
               {"redundant_policy", "fixed at nominal"},
               {"iterations", fit.iterations},
               {"stop", stopReasonText(fit.stop)},
               {"rms_before_mm", fit.before.rms_mm},
               {"rms_mm", fit.after.rms_mm},
               {"max_abs_residual_mm", fit.after.max_abs_mm},
               {"mean_residual_mm", fit.after.mean_mm},
               {"sigma_mm", fit.sigma_mm},
               {"condition_number", fit.condition_number},
               {"o1", fit.o1},
               {"o3", fit.o3},
               {"predicted_ball_error_rms_mm", a.predicted_ball_error_rms_mm},
               {"predicted_ball_error_max_mm", a.predicted_ball_error_max_mm},
               {"bar_to_endpoint_factor", a.bar_to_endpoint_factor},
               {"outlier_sigmas", a.outlier_sigmas}};
  ojson patterns = ojson::array();
  for (const AdequacyPattern& p : a.adequacy.patterns)
    patterns.push_back({{"pattern", p.pattern},
                        {"detail", p.detail},
                        {"found", p.found},
                        {"chi2", p.chi2},
                        {"threshold", p.threshold},
                        {"rms_mm", p.rms_mm}});
  // noise_mm: the bar's noise measured by revisits of points (null without revisits).
  const Adequacy& ad = a.adequacy;
  out["adequacy"] = {
      {"ok", ad.ok},
      {"noise_mm", ad.noise_mm ? ojson(*ad.noise_mm) : ojson(nullptr)},
      {"revisited_places", ad.revisited_places},
      {"noise_dof", ad.noise_dof},
      {"fit_over_noise", ad.fit_over_noise_limit > 0 ? ojson(ad.fit_over_noise) : ojson(nullptr)},
      {"fit_over_noise_limit",
       ad.fit_over_noise_limit > 0 ? ojson(ad.fit_over_noise_limit) : ojson(nullptr)},
      {"lack_of_fit", ad.lack_of_fit},
      {"sigma_mm", a.adequacy.sigma_mm},
      {"lack_of_fit_mm", a.adequacy.unmodelled_bar_mm()},
      {"summary", a.adequacy.summary()},
      {"patterns", patterns},
      {"drift", driftJson(ad.drift)}};
  if (a.compliance) {
    const ComplianceEstimate& c = *a.compliance;
    ojson joints = ojson::array();
    for (int j : c.joints)
      joints.push_back({{"joint", j + 1},
                        {"deg_per_nm", c.fitted_deg_per_nm[j]},
                        {"sigma_deg_per_nm", c.sigma_deg_per_nm[j]}});
    out["compliance"] = {{"identified", c.identified},
                         {"chi2", c.chi2},
                         {"chi2_threshold", c.chi2_threshold},
                         {"joints", joints},
                         {"largest_twist_deg", c.largest_twist_deg},
                         {"largest_twist_sigma_deg", c.largest_twist_sigma_deg},
                         {"payload_kg", c.compliance.load.payload_kg},
                         {"summary", c.summary()}};
  }
  ojson outliers = ojson::array();
  for (const FlaggedOutlier& o : a.outliers) {
    ojson j = sampleRef(o.sample);
    j["residual_mm"] = o.residual_mm;
    j["robust_sigmas"] = o.robust_sigmas;
    outliers.push_back(j);
  }
  out["outliers"] = outliers;
  out["dropped"] = a.outliers_dropped ? a.outliers.size() : 0;
  out["worst_shells"] = worstJson(a.shells);
  out["shells"] = shellsJson(a.shells);
  out["parameter_table"] = parameterTableJson(a.parameters);
  if (a.validation) {
    const ValidationResult& v = *a.validation;
    out["validation_description"] = v.description;
    out["validation_n"] = v.stats.count;
    out["validation_rms_mm"] = v.stats.rms_mm;
    out["validation_max_abs_mm"] = v.stats.max_abs_mm;
    out["validation_worst_shells"] = worstJson(v.shells);
    out["validation_shells"] = shellsJson(v.shells);
  }
  if (a.truth) {
    out["truth_poses"] = a.truth->poses;
    out["truth_nominal_rms_mm"] = a.truth->nominal_rms_mm;
    out["truth_calibrated_rms_mm"] = a.truth->calibrated_rms_mm;
    out["truth_calibrated_max_mm"] = a.truth->calibrated_max_mm;
  }
  return out;
}

ResultVerdict fitOnlyVerdict(const FitAssessment& a) {
  ResultVerdict v;
  v.usable = a.problems.empty();
  v.problems = a.problems;
  v.rank = a.fit.identifiability.rank;
  v.expected_rank = a.fit.identifiability.expected;
  return v;
}

void writeReport(const std::string& dir, const FitAssessment& a, const Model& calibrated,
                 const ReportExtras& extras) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw FormatError(dir + ": cannot create the report folder: " + ec.message());
  const ojson summary = fitSummaryJson(a);
  ojson report = {{"summary", summary}, {"figures", ojson::object()}};
  std::vector<Figure> figures;
  auto add = [&](const std::string& key, const std::string& caption, auto&& make) {
    Figure f{key + ".svg", caption, {}};
    report["figures"][key] = make(caption, &f.svg);
    writeTextFileAtomic(dir + "/" + f.file, f.svg);
    figures.push_back(std::move(f));
  };
  const auto& r = a.fit.residuals;
  add("residuals_vs_longitude", "Residual against longitude, fitted samples",
      [&](const std::string& t, std::string* s) { return longitudeFigure(a.samples, r, t, s); });
  add("residual_histogram", "Residual distribution, fitted samples",
      [&](const std::string& t, std::string* s) { return histogramFigure(r, t, s); });
  add("shell_rms", "Residual per shell, fitted samples",
      [&](const std::string& t, std::string* s) { return shellFigure(a.shells, t, s); });
  if (a.validation) {
    const ValidationResult& v = *a.validation;
    add("validation_vs_longitude", "Residual against longitude, " + v.description,
        [&](const std::string& t, std::string* s) {
          return longitudeFigure(v.samples, v.residuals, t, s);
        });
    add("validation_histogram", "Residual distribution, " + v.description,
        [&](const std::string& t, std::string* s) { return histogramFigure(v.residuals, t, s); });
    add("validation_shell_rms", "Residual per shell, " + v.description,
        [&](const std::string& t, std::string* s) { return shellFigure(v.shells, t, s); });
  }
  figures.insert(figures.end(), extras.figures.begin(), extras.figures.end());
  const ResultVerdict verdict = extras.verdict ? *extras.verdict : fitOnlyVerdict(a);
  report["verdict"] = resultVerdictJson(verdict);
  writeTextFileAtomic(dir + "/summary.html",
                      report_detail::summaryHtml(a, calibrated, verdict, figures));
  writeTextFileAtomic(dir + "/report.json", report.dump(1) + "\n");
}

}  // namespace robocal
