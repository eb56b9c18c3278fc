#include <robocal/solver/assessment.hpp>
#include <robocal/solver/verdict.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace robocal {
namespace {

std::string number(const char* format, double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, value);
  return buf;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

std::string where(const Sample& s) {
  return s.source.empty() ? std::string("in memory")
                          : s.source + ":" + std::to_string(s.source_line);
}

}  // namespace

std::optional<std::string> samplesUnitsProblem(const Model& nominal,
                                               const std::vector<Sample>& samples) {
  if (samples.size() < 10) return std::nullopt;
  // A calibration's poses sweep the joints over tens of degrees: every reading within one turn
  // in radians (6.3) is radians.
  double max_abs_joint = 0;
  for (const Sample& s : samples)
    max_abs_joint = std::max(max_abs_joint, s.joints_deg.cwiseAbs().maxCoeff());
  if (max_abs_joint <= 2 * M_PI + 0.01)
    return "every joint reading of these " + std::to_string(samples.size()) +
           " samples lies within +/-" + number("%.2f", max_abs_joint) +
           ", as if in radians (first at " + where(samples.front()) +
           "); samples hold joints in degrees (docs/samples-format.md): convert them (x 57.2958) "
           "and fit again";
  // Bar lengths a thousandth of the nominal model's are metres.
  const Eigen::VectorXd residuals = sampleResiduals(nominal, samples);
  std::vector<double> ratios;
  for (size_t i = 0; i < samples.size(); ++i) {
    const double predicted_mm = samples[i].length_mm - residuals[static_cast<Eigen::Index>(i)];
    if (predicted_mm > 0) ratios.push_back(samples[i].length_mm / predicted_mm);
  }
  const double ratio = median(ratios);
  if (ratio > 1e-4 && ratio < 1e-2)
    return "the bar lengths are " + number("%.4g", ratio) +
           " times the nominal model's (median), as if in metres (first at " +
           where(samples.front()) +
           "); samples hold lengths in mm (docs/samples-format.md): convert them (x 1000) and "
           "fit again";
  return std::nullopt;
}

std::vector<std::string> fitProblems(const FitAssessment& a, const VerdictLimits& limits) {
  std::vector<std::string> out;
  if (auto units = samplesUnitsProblem(a.nominal, a.samples)) out.push_back(*units);
  const Identifiability& id = a.fit.identifiability;
  const size_t n = a.samples.size();
  if (id.rank < id.expected) {
    const auto& cs = a.connections;
    out.push_back("rank " + std::to_string(id.rank) + " of the " + std::to_string(id.expected) +
                  " independent parameters: these " + std::to_string(n) + " samples on " +
                  std::to_string(cs.size()) + " of the 9 connections (" + connectionList(cs) +
                  ") leave " + std::to_string(id.expected - id.rank) +
                  " of them unidentified, held at nominal, so the model is only partly "
                  "calibrated; measure all nine connections, or six that use every ball and "
                  "every chuck, on enough points (docs/identifiability.md)");
  }
  const double needed = limits.min_samples_per_parameter * id.rank;
  if (id.rank > 0 && static_cast<double>(n) < needed)
    out.push_back(std::to_string(n) + " samples for " + std::to_string(id.rank) +
                  " identified parameters leave " +
                  std::to_string(n - std::min<size_t>(n, id.rank)) +
                  " degrees of freedom: the fit can match them whatever the robot is, so its "
                  "residual and predicted error say nothing; measure at least " +
                  number("%.0f", std::ceil(needed)) +
                  " points (robocal plan's default plan has "
                  "over 1,500)");
  if (a.fit.after.rms_mm > limits.max_fit_rms_mm)
    out.push_back("the fit's RMS residual is " + number("%.3g", a.fit.after.rms_mm) +
                  " mm, far above a ball-bar's noise (0.05-0.1 mm; limit " +
                  number("%.3g", limits.max_fit_rms_mm) +
                  " mm): the model does not describe these data; check the units, the "
                  "connection labels (which ball on which chuck) and the model file");
  const Adequacy& ad = a.adequacy;
  if (ad.noise_mm && ad.lack_of_fit && ad.fit_over_noise > limits.max_fit_over_noise)
    out.push_back("the fit's residual, " + number("%.3g", ad.sigma_mm) + " mm, is " +
                  number("%.2g", ad.fit_over_noise) + " times the bar's noise that " +
                  std::to_string(ad.revisited_places) + " revisited places measured (" +
                  number("%.3g", *ad.noise_mm) + " mm; at most " +
                  number("%.2g", limits.max_fit_over_noise) +
                  " times): " + number("%.2g", ad.unmodelled_bar_mm()) +
                  " mm of error along the bar that the model does not contain, which every "
                  "compensated position would carry; check the balls' and chucks' positions "
                  "and the bar's extension in the model file, a loose ball or chuck, and the "
                  "settling (docs/real-cell.md), then measure again");
  if (!a.outliers.empty() && !a.outliers_dropped) {
    const auto worst = std::max_element(a.outliers.begin(), a.outliers.end(),
                                        [](const FlaggedOutlier& x, const FlaggedOutlier& y) {
                                          return std::abs(x.residual_mm) < std::abs(y.residual_mm);
                                        });
    out.push_back(std::to_string(a.outliers.size()) + " outlier" +
                  (a.outliers.size() == 1 ? "" : "s") + " beyond " +
                  number("%.3g", a.outlier_sigmas) + " robust sigmas kept in the fit (the worst " +
                  number("%+.3g", worst->residual_mm) + " mm at " + where(worst->sample) +
                  ") pull every parameter toward it; check those samples, then fit again "
                  "without them (robocal solve --drop-outliers) or measure them again");
  }
  const double nominal_mm = a.fit.before.rms_mm;
  if (!(a.predicted_ball_error_rms_mm <= nominal_mm))
    out.push_back("the predicted 1-sigma ball-position error, RMS " +
                  number("%.4g", a.predicted_ball_error_rms_mm) +
                  " mm, exceeds the nominal model's error on these samples (RMS residual " +
                  number("%.4g", nominal_mm) +
                  " mm): the data cannot pin the parameters, so the calibrated model could be "
                  "less accurate than the nominal; measure more points");
  return out;
}

}  // namespace robocal
