#include <robocal/solver/health.hpp>

#include <robocal/solver/problem.hpp>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace robocal {
namespace {

std::string fmt(const char* format, double a, double b = 0, double c = 0, double d = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, format, a, b, c, d);
  return buf;
}

void checkOptions(const HealthOptions& o) {
  auto positive = [](const char* key, double v) {
    if (!(v > 0) || !std::isfinite(v))
      throw std::invalid_argument(std::string("health options: ") + key + " must be positive");
  };
  if (o.baseline_rms_mm) positive("baseline_rms_mm", *o.baseline_rms_mm);
  positive("fallback_rms_mm", o.fallback_rms_mm);
  positive("warn_ratio", o.warn_ratio);
  positive("fail_ratio", o.fail_ratio);
  if (o.fail_ratio < o.warn_ratio)
    throw std::invalid_argument("health options: fail_ratio must not be below warn_ratio");
  positive("prior_translation_mm", o.prior_translation_mm);
  positive("prior_link_angle_deg", o.prior_link_angle_deg);
  positive("prior_joint_offset_deg", o.prior_joint_offset_deg);
  positive("prior_gain", o.prior_gain);
  positive("significance", o.significance);
  if (!(o.equivalent_cosine > 0 && o.equivalent_cosine <= 1))
    throw std::invalid_argument("health options: equivalent_cosine must be in (0, 1]");
  if (o.max_iterations < 1)
    throw std::invalid_argument("health options: max_iterations must be at least 1");
}

// The small refit: forward selection of the parameters that explain the residuals, each refitted
// with the prior from the active model (docs/health-check.md, "What moved").
void nameWhatMoved(const Model& active, const std::vector<Sample>& samples,
                   const HealthOptions& options, HealthVerdict& v) {
  // solveCalibration weighs a sample's residual (mm) as one unit against a prior row
  // (start - p) / prior_sigma; dividing the prior sigmas by the noise level (mm) makes its cost
  // noise^2 times sum (r / noise)^2 + sum ((p - start) / prior)^2, the proper posterior.
  const double noise = v.reference_rms_mm;
  const ParamVector prior = paramSigmas(options.prior_translation_mm, options.prior_link_angle_deg,
                                        options.prior_joint_offset_deg, options.prior_gain);
  SolveOptions solve;
  solve.prior_sigma = prior / noise;
  solve.max_iterations = options.max_iterations;

  const ParamVector start = toParams(active);
  std::vector<int> selected;
  SolveResult fit;
  Eigen::VectorXd r;
  Eigen::MatrixXd jac;
  evaluateProblem(active, start, samples, r, &jac);
  v.refit_rms_mm = v.residuals.rms_mm;
  const Eigen::VectorXd column_norm = jac.colwise().norm().transpose();
  const double min_score = options.significance * options.significance;
  while (static_cast<int>(selected.size()) < options.max_named) {
    // An orthonormal basis of the chosen columns, and what of r and of each other column lies
    // outside their span.
    Eigen::MatrixXd q(jac.rows(), 0);
    if (!selected.empty()) {
      Eigen::MatrixXd chosen(jac.rows(), static_cast<Eigen::Index>(selected.size()));
      for (size_t k = 0; k < selected.size(); ++k)
        chosen.col(static_cast<Eigen::Index>(k)) = jac.col(selected[k]);
      const Eigen::HouseholderQR<Eigen::MatrixXd> qr(chosen);
      q = qr.householderQ() * Eigen::MatrixXd::Identity(chosen.rows(), chosen.cols());
    }
    const Eigen::VectorXd rest = r - q * (q.transpose() * r);
    // The chi^2 a one-parameter prior-weighted step along each column would remove.
    int best = -1;
    double best_score = 0;
    for (int i = 0; i < kParamCount; ++i) {
      if (std::find(selected.begin(), selected.end(), i) != selected.end()) continue;
      const Eigen::VectorXd col = jac.col(i) - q * (q.transpose() * jac.col(i));
      if (col.norm() <= 1e-6 * column_norm[i]) continue;  // nothing new: same as the chosen
      const double along = col.dot(rest);
      const double score =
          along * along / (col.squaredNorm() + std::pow(noise / prior[i], 2)) / (noise * noise);
      if (score > best_score) {
        best_score = score;
        best = i;
      }
    }
    if (best < 0 || best_score < min_score) break;
    selected.push_back(best);
    solve.fixed.clear();
    for (int i = 0; i < kParamCount; ++i)
      if (std::find(selected.begin(), selected.end(), i) == selected.end())
        solve.fixed.push_back(i);
    fit = solveCalibration(active, samples, solve);
    v.refit_rms_mm = fit.after.rms_mm;
    evaluateProblem(active, fit.params, samples, r, &jac);
  }
  if (selected.empty()) return;

  // The covariance solveCalibration reports is s^2 (J^T J + noise^2 / prior^2)^-1 with s the
  // refit's RMS; the posterior takes the noise level, or that RMS when it is larger (residuals the
  // refit cannot explain make every change less certain).
  const double sigma = std::max(noise, fit.sigma_mm);
  const double scale = fit.sigma_mm > 0 ? std::pow(sigma / fit.sigma_mm, 2) : 1.0;
  for (int i : selected) {
    ParamVector unit = ParamVector::Zero();
    unit[i] = 1;
    const double to_interface = paramInterfaceValue(unit, i);  // 1, or deg per rad
    ParameterChange c;
    c.index = i;
    c.name = paramName(i);
    c.unit = paramKind(i) == ParamKind::kGain ? "gain" : paramUnit(i);
    c.change = (fit.params[i] - start[i]) * to_interface;
    c.sigma = std::sqrt(std::max(0.0, fit.covariance(i, i) * scale)) * to_interface;
    c.prior_sigma = prior[i] * to_interface;
    c.significance = c.sigma > 0 ? std::abs(c.change) / c.sigma : 0;
    c.prior_ratio = std::abs(c.change) / c.prior_sigma;
    c.text = parameterChangeText(i, c.change);
    for (int k = 0; k < kParamCount; ++k) {
      if (k == i || column_norm[i] == 0 || column_norm[k] == 0) continue;
      const double cosine = jac.col(i).dot(jac.col(k)) / (jac.col(i).norm() * jac.col(k).norm());
      if (std::abs(cosine) >= options.equivalent_cosine) c.equivalent.push_back(paramName(k));
    }
    v.moved.push_back(std::move(c));
  }
  std::stable_sort(v.moved.begin(), v.moved.end(),
                   [](const ParameterChange& a, const ParameterChange& b) {
                     return a.significance > b.significance;
                   });
}

}  // namespace

const char* healthStatusName(HealthStatus status) {
  switch (status) {
    case HealthStatus::kPass:
      return "pass";
    case HealthStatus::kWarn:
      return "warn";
    case HealthStatus::kFail:
      return "fail";
  }
  return "?";
}

const char* healthReferenceName(HealthReference reference) {
  switch (reference) {
    case HealthReference::kBaseline:
      return "baseline";
    case HealthReference::kCalibration:
      return "calibration";
    case HealthReference::kFallback:
      return "fallback";
  }
  return "?";
}

std::string parameterChangeText(int index, double change) {
  switch (paramKind(index)) {
    case ParamKind::kTranslation:
      return paramName(index) + fmt(" %+.3f mm", change);
    case ParamKind::kAngle:
      return paramName(index) + fmt(" %+.4f deg", change);
    case ParamKind::kGain:
      break;
  }
  return paramName(index) + fmt(" %+.6f", change);
}

HealthVerdict assessHealth(const Model& active, const std::vector<Sample>& check_samples,
                           const HealthOptions& options) {
  checkOptions(options);
  HealthVerdict v;
  const Eigen::VectorXd residuals = sampleResiduals(active, check_samples);  // checks the samples
  v.samples = check_samples.size();
  v.residuals = residualStats(residuals);
  v.shells = shellTable(check_samples, residuals);
  for (const Connection& c : allConnections())
    if (std::any_of(check_samples.begin(), check_samples.end(), [&](const Sample& s) {
          return s.ball_index == c.ball_index && s.chuck_index == c.chuck_index;
        }))
      v.connections.push_back(c);
  for (const Sample& s : check_samples)
    if (std::none_of(v.extensions_mm.begin(), v.extensions_mm.end(),
                     [&](double e) { return std::abs(e - s.extension_mm) < 1e-9; }))
      v.extensions_mm.push_back(s.extension_mm);
  std::sort(v.extensions_mm.begin(), v.extensions_mm.end());

  if (options.baseline_rms_mm) {
    v.reference = HealthReference::kBaseline;
    v.reference_rms_mm = *options.baseline_rms_mm;
  } else if (active.provenance && active.provenance->rms_mm > 0 &&
             std::isfinite(active.provenance->rms_mm)) {
    v.reference = HealthReference::kCalibration;
    v.reference_rms_mm = active.provenance->rms_mm;
  } else {
    v.reference = HealthReference::kFallback;
    v.reference_rms_mm = options.fallback_rms_mm;
  }
  v.rms_ratio = v.residuals.rms_mm / v.reference_rms_mm;
  v.ratio_scatter = 1.0 / std::sqrt(2.0 * static_cast<double>(v.samples));
  v.warn_ratio = options.warn_ratio;
  v.fail_ratio = options.fail_ratio;

  nameWhatMoved(active, check_samples, options, v);
  v.refit_ratio = v.refit_rms_mm / v.reference_rms_mm;

  const std::string level =
      fmt("RMS %.4f mm is %.2f times ", v.residuals.rms_mm, v.rms_ratio) +
      (v.reference == HealthReference::kBaseline      ? "the baseline check's RMS"
       : v.reference == HealthReference::kCalibration ? "the calibration's fit RMS"
                                                      : "the fallback reference") +
      fmt(" of %.4f mm", v.reference_rms_mm);
  if (static_cast<int>(v.samples) < options.min_samples) {
    v.status = HealthStatus::kWarn;
    v.reason =
        fmt("%.0f samples are too few to judge (at least %.0f): ", static_cast<double>(v.samples),
            options.min_samples) +
        level;
  } else if (v.rms_ratio >= options.fail_ratio) {
    v.status = HealthStatus::kFail;
    v.reason = level + fmt(", at or above %.2f: the model no longer fits the robot; recalibrate",
                           options.fail_ratio);
  } else if (v.rms_ratio >= options.warn_ratio) {
    v.status = HealthStatus::kWarn;
    v.reason = level + fmt(", at or above %.2f (fail from %.2f): the robot may have changed; "
                           "check again, recalibrate if it persists",
                           options.warn_ratio, options.fail_ratio);
  } else {
    v.status = HealthStatus::kPass;
    v.reason = level + fmt(", below %.2f: the model still fits the robot", options.warn_ratio);
  }
  return v;
}

}  // namespace robocal
