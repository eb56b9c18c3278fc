#include <robocal/formats/report.hpp>

#include <robocal/formats/error.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <numbers>

namespace robocal {
namespace {

using ojson = nlohmann::ordered_json;

std::string fmt(const char* format, double a, double b = 0, double c = 0, double d = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, format, a, b, c, d);
  return buf;
}

// A minimal SVG chart: a plot area with axes, ticks and labels, in data coordinates.
class SvgChart {
 public:
  SvgChart(std::string title, std::string x_label, std::string y_label, double x0, double x1,
           double y0, double y1)
      : x0_(x0), x1_(x1), y0_(y0), y1_(y1) {
    body_ += "<text x='400' y='24' text-anchor='middle' font-size='16'>" + title + "</text>\n";
    body_ += "<text x='400' y='490' text-anchor='middle' font-size='13'>" + x_label + "</text>\n";
    body_ +=
        "<text x='18' y='250' text-anchor='middle' font-size='13' transform='rotate(-90 18 250)'>" +
        y_label + "</text>\n";
    body_ += fmt("<rect x='%g' y='%g' width='%g' height='%g' fill='none' stroke='black'/>\n", kLeft,
                 kTop, kRight - kLeft, kBottom - kTop);
    for (int i = 0; i <= 6; ++i) {
      const double xv = x0 + (x1 - x0) * i / 6, yv = y0 + (y1 - y0) * i / 6;
      body_ += fmt("<text x='%g' y='%g' text-anchor='middle' font-size='11'>%.4g</text>\n", px(xv),
                   kBottom + 16, xv);
      body_ += fmt("<text x='%g' y='%g' text-anchor='end' font-size='11'>%.3g</text>\n", kLeft - 4,
                   py(yv) + 4, yv);
    }
    if (y0 < 0 && y1 > 0)
      body_ += fmt("<line x1='%g' y1='%g' x2='%g' y2='%g' stroke='#999'/>\n", kLeft, py(0), kRight,
                   py(0));
  }
  double px(double x) const { return kLeft + (x - x0_) / (x1_ - x0_) * (kRight - kLeft); }
  double py(double y) const { return kBottom - (y - y0_) / (y1_ - y0_) * (kBottom - kTop); }
  void dot(double x, double y, const std::string& colour) {
    body_ += fmt("<circle cx='%.1f' cy='%.1f' r='2.2' fill='", px(x), py(y)) + colour + "'/>\n";
  }
  void bar(double xa, double xb, double h) {
    body_ += fmt(
        "<rect x='%.1f' y='%.1f' width='%.1f' height='%.1f' fill='#9ecae1' stroke='#3182bd'/>\n",
        px(xa), py(h), px(xb) - px(xa), py(0) - py(h));
  }
  void polyline(const std::vector<std::pair<double, double>>& points, const std::string& colour) {
    body_ += "<polyline fill='none' stroke-width='2' stroke='" + colour + "' points='";
    for (const auto& [x, y] : points) body_ += fmt("%.1f,%.1f ", px(x), py(y));
    body_ += "'/>\n";
  }
  void legend(int row, const std::string& text, const std::string& colour) {
    const double y = kTop + 14 + 15 * row;
    body_ += fmt("<circle cx='%g' cy='%g' r='4' fill='", kRight + 12, y - 4) + colour + "'/>\n";
    body_ += fmt("<text x='%g' y='%g' font-size='11'>", kRight + 20, y) + text + "</text>\n";
  }
  void note(int row, const std::string& text) {
    body_ += fmt("<text x='%g' y='%g' font-size='12'>", kLeft + 8, kTop + 18 + 16 * row) + text +
             "</text>\n";
  }
  std::string svg() const {
    return "<svg xmlns='http://www.w3.org/2000/svg' width='900' height='500' "
           "font-family='sans-serif'>\n"
           "<rect width='900' height='500' fill='white'/>\n" +
           body_ + "</svg>\n";
  }

 private:
  static constexpr double kLeft = 70, kRight = 680, kTop = 40, kBottom = 450;
  double x0_, x1_, y0_, y1_;
  std::string body_;
};

const std::vector<std::string> kPalette = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                           "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};

double symmetricLimit(const Eigen::VectorXd& r) {
  const double m = r.size() ? r.cwiseAbs().maxCoeff() : 1.0;
  return m > 0 ? m * 1.1 : 1.0;
}

// Figure 3: residual against longitude, one series per shell.
ojson longitudeFigure(const std::vector<Sample>& samples, const Eigen::VectorXd& r,
                      const std::string& title, std::string* svg) {
  const double lim = symmetricLimit(r);
  SvgChart chart(title, "longitude (deg)", "residual (mm)", 0, 360, -lim, lim);
  std::map<int, ojson> series;
  std::map<int, std::string> names;
  for (size_t i = 0; i < samples.size(); ++i) {
    const Sample& s = samples[i];
    ojson& shell = series[s.shell];
    if (shell.is_null()) shell = {{"lon_deg", ojson::array()}, {"residual_mm", ojson::array()}};
    shell["lon_deg"].push_back(s.lon_deg);
    shell["residual_mm"].push_back(r[static_cast<Eigen::Index>(i)]);
    names[s.shell] = connectionName({s.ball_index, s.chuck_index}) +
                     (s.extension_mm > 0 ? fmt(" +%.0f mm", s.extension_mm) : "");
  }
  ojson out = {{"x", "lon_deg"}, {"y", "residual_mm"}, {"series", ojson::array()}};
  int row = 0;
  for (const auto& [shell, data] : series) {
    const std::string& colour = kPalette[row % kPalette.size()];
    for (size_t k = 0; k < data["lon_deg"].size(); ++k)
      chart.dot(std::fmod(data["lon_deg"][k].get<double>() + 360.0, 360.0),
                data["residual_mm"][k].get<double>(), colour);
    chart.legend(row++, "shell " + std::to_string(shell) + " " + names[shell], colour);
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
  SvgChart chart(title, "residual (mm)", "samples per bin", -lim, lim, 0, top);
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

ojson names(const std::vector<int>& indices) {
  ojson out = ojson::array();
  for (int i : indices) out.push_back(paramName(i));
  return out;
}

ojson sampleRef(const Sample& s) {
  return {{"file", s.source}, {"line", s.source_line}, {"shell", s.shell}};
}

}  // namespace

nlohmann::ordered_json fitSummaryJson(const FitReport& r) {
  const SolveResult& fit = r.fit;
  ojson out = {{"class", "RESULT"},
               {"n", fit.after.count},
               {"rank", fit.identifiability.rank},
               {"parameters", kParamCount},
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
               {"predicted_ball_error_rms_mm", r.ball_error_rms_mm},
               {"predicted_ball_error_max_mm", r.ball_error_max_mm},
               {"bar_to_endpoint_factor", r.bar_to_endpoint_factor},
               {"outlier_sigmas", r.outlier_sigmas}};
  ojson outliers = ojson::array();
  for (size_t i = 0; i < r.outliers.size(); ++i) {
    const Sample& s = r.dropped.empty() ? r.samples[r.outliers[i].index] : r.dropped[i];
    ojson o = sampleRef(s);
    o["residual_mm"] = r.outliers[i].residual_mm;
    o["robust_sigmas"] = r.outliers[i].robust_sigmas;
    outliers.push_back(o);
  }
  out["outliers"] = outliers;
  out["dropped"] = r.dropped.size();
  if (!r.validation.empty()) {
    const ResidualStats v = residualStats(r.validation_residuals);
    out["validation_n"] = v.count;
    out["validation_rms_mm"] = v.rms_mm;
    out["validation_max_abs_mm"] = v.max_abs_mm;
  }
  if (r.truth.poses > 0) {
    out["truth_poses"] = r.truth.poses;
    out["truth_nominal_rms_mm"] = r.truth.nominal_rms_mm;
    out["truth_calibrated_rms_mm"] = r.truth.calibrated_rms_mm;
    out["truth_calibrated_max_mm"] = r.truth.calibrated_max_mm;
  }
  return out;
}

void writeReport(const std::string& dir, const FitReport& r) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw FormatError(dir + ": cannot create the report folder: " + ec.message());
  ojson report = {{"summary", fitSummaryJson(r)}, {"figures", ojson::object()}};
  std::string svg;
  report["figures"]["residuals_vs_longitude"] = longitudeFigure(
      r.samples, r.fit.residuals, "Residual against longitude (fitted samples)", &svg);
  writeTextFileAtomic(dir + "/residuals_vs_longitude.svg", svg);
  report["figures"]["residual_histogram"] =
      histogramFigure(r.fit.residuals, "Residual distribution (fitted samples)", &svg);
  writeTextFileAtomic(dir + "/residual_histogram.svg", svg);
  if (!r.validation.empty()) {
    report["figures"]["validation_vs_longitude"] = longitudeFigure(
        r.validation, r.validation_residuals, "Validation residual against longitude", &svg);
    writeTextFileAtomic(dir + "/validation_vs_longitude.svg", svg);
    report["figures"]["validation_histogram"] =
        histogramFigure(r.validation_residuals, "Validation residual distribution", &svg);
    writeTextFileAtomic(dir + "/validation_histogram.svg", svg);
  }
  writeTextFileAtomic(dir + "/report.json", report.dump(1) + "\n");
}

}  // namespace robocal
