#include <robocal/solver/health.hpp>

#include <robocal/kinematics/twist.hpp>
#include <robocal/solver/problem.hpp>

#include <Eigen/Cholesky>
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
  if (!(o.alternative_chi2 >= 0) || !std::isfinite(o.alternative_chi2))
    throw std::invalid_argument("health options: alternative_chi2 must be 0 or more");
  if (!(o.equivalent_cosine > 0 && o.equivalent_cosine <= 1))
    throw std::invalid_argument("health options: equivalent_cosine must be in (0, 1]");
  if (o.max_iterations < 1)
    throw std::invalid_argument("health options: max_iterations must be at least 1");
}

// The refit's prior: how far each parameter is expected to move (ParamVector units).
ParamVector priorSigmas(const HealthOptions& o) {
  return paramSigmas(o.prior_translation_mm, o.prior_link_angle_deg, o.prior_joint_offset_deg,
                     o.prior_gain);
}

// The small refit: forward selection of the parameters that explain the residuals, each refitted
// with the prior from the active model, at the noise level `noise` (docs/health-check.md, "What
// moved").
struct Named {
  std::vector<int> selected;
  // For each selected one, the others whose one-parameter step explained the residual nearly as
  // well at its turn (score within HealthOptions::alternative_chi2): the data cannot tell them
  // apart.
  std::vector<std::vector<int>> alternatives;
  SolveResult fit;      // of the selected ones (empty when none)
  Eigen::VectorXd r;    // the residuals after it
  Eigen::MatrixXd jac;  // and their Jacobian
  double rms_mm = 0;    // RMS of r
};

// The Student t quantile with `dof` degrees of freedom whose tail is the normal's beyond z
// (Cornish-Fisher; at z = 3.5 within 0.02 of the exact quantile at 10 degrees of freedom, 0.001
// from 20).
double studentEquivalent(double z, double dof) {
  if (!(dof > 0)) return z;
  const double z2 = z * z, z3 = z2 * z, z5 = z3 * z2, z7 = z5 * z2;
  return z + (z3 + z) / (4 * dof) + (5 * z5 + 16 * z3 + 3 * z) / (96 * dof * dof) +
         (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / (384 * dof * dof * dof);
}

Named selectMoved(const Model& active, const std::vector<Sample>& samples,
                  const HealthOptions& options, double noise, double significance) {
  // solveCalibration weighs a sample's residual (mm) as one unit against a prior row
  // (start - p) / prior_sigma; dividing the prior sigmas by the noise level (mm) makes its cost
  // noise^2 times sum (r / noise)^2 + sum ((p - start) / prior)^2, the proper posterior.
  const ParamVector prior = priorSigmas(options);
  SolveOptions solve;
  solve.prior_sigma = prior / noise;
  solve.max_iterations = options.max_iterations;

  Named out;
  evaluateProblem(active, toParams(active), samples, out.r, &out.jac);
  out.rms_mm = std::sqrt(out.r.squaredNorm() / static_cast<double>(out.r.size()));
  const Eigen::VectorXd column_norm = out.jac.colwise().norm().transpose();
  const double min_score = significance * significance;
  // The active model is itself uncertain (its covariance C): on an unchanged robot the residuals
  // scatter as noise^2 (I + J C J^T / noise^2), not as white noise, and the calibration's own
  // error at the check's poses must not be named as a change. The test runs on residuals and
  // columns whitened by L^-1, L L^T = I + J C J^T / noise^2 (identity without a covariance).
  const Eigen::Index n = out.jac.rows();
  Eigen::LLT<Eigen::MatrixXd> whitening(Eigen::MatrixXd::Identity(n, n));
  if (hasParamCovariance(active)) {
    // With the twists' columns when the model takes a twist: the twist and what it moved the
    // offsets by cancel at the shells' poses, which the 54's block alone would not see. A twist
    // the fit did not keep is judged as the calibration took it, known: whatever of it is there
    // was there at the calibration too, and its uncertainty would hide a change of joints 2-3
    // (a 0.02 deg J2.offset seen in 28 of 30 checks with it, 30 of 30 without).
    const bool twists = active.compliance && active.compliance->twists();
    // The twists the fit did not look for (the wrist's, at a prior's size) likewise: they are
    // whatever they were at the calibration.
    const Eigen::MatrixXd c = twists ? withoutUnfittedTwists(*active.covariance)
                                     : covarianceAtKnownTwist(*active.covariance);
    Eigen::MatrixXd jac = out.jac;
    if (hasTwistRows(c)) {
      jac.conservativeResize(n, c.cols());
      const RigidGravityTorque torque_nm(active);
      for (Eigen::Index i = 0; i < n; ++i)
        jac.row(i).tail<kJointCount>() =
            twistColumns(out.jac.row(i), torque_nm(samples[static_cast<size_t>(i)].joints_deg));
    }
    whitening.compute(Eigen::MatrixXd::Identity(n, n) +
                      jac * c * jac.transpose() / (noise * noise));
  }
  std::vector<int>& selected = out.selected;
  while (static_cast<int>(selected.size()) < options.max_named) {
    const Eigen::MatrixXd jac = whitening.matrixL().solve(out.jac);
    const Eigen::VectorXd r = whitening.matrixL().solve(out.r);
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
    Eigen::VectorXd scores = Eigen::VectorXd::Zero(kParamCount);
    for (int i = 0; i < kParamCount; ++i) {
      if (std::find(selected.begin(), selected.end(), i) != selected.end()) continue;
      const Eigen::VectorXd col = jac.col(i) - q * (q.transpose() * jac.col(i));
      if (col.norm() <= 1e-6 * column_norm[i]) continue;  // nothing new: same as the chosen
      const double along = col.dot(rest);
      scores[i] =
          along * along / (col.squaredNorm() + std::pow(noise / prior[i], 2)) / (noise * noise);
      if (scores[i] > best_score) {
        best_score = scores[i];
        best = i;
      }
    }
    if (best < 0 || best_score < min_score) break;
    selected.push_back(best);
    std::vector<int> close;
    for (int i = 0; i < kParamCount; ++i)
      if (i != best && scores[i] > 0 && scores[i] >= best_score - options.alternative_chi2)
        close.push_back(i);
    out.alternatives.push_back(std::move(close));
    solve.fixed.clear();
    for (int i = 0; i < kParamCount; ++i)
      if (std::find(selected.begin(), selected.end(), i) == selected.end())
        solve.fixed.push_back(i);
    out.fit = solveCalibration(active, samples, solve);
    out.rms_mm = out.fit.after.rms_mm;
    evaluateProblem(active, out.fit.params, samples, out.r, &out.jac);
  }
  return out;
}

// The named changes of `named`, most significant first, with the data's equivalents.
void describeMoved(const Model& active, const HealthOptions& options, const Named& named,
                   double noise, HealthVerdict& v) {
  if (named.selected.empty()) return;
  const ParamVector prior = priorSigmas(options);
  const ParamVector start = toParams(active);
  const SolveResult& fit = named.fit;
  const Eigen::MatrixXd& jac = named.jac;
  // The covariance solveCalibration reports is s^2 (J^T J + noise^2 / prior^2)^-1 with s the
  // refit's RMS; the posterior takes the noise level, or that RMS when it is larger (residuals the
  // refit cannot explain make every change less certain).
  const double sigma = std::max(noise, fit.sigma_mm);
  const double scale = fit.sigma_mm > 0 ? std::pow(sigma / fit.sigma_mm, 2) : 1.0;
  for (size_t n = 0; n < named.selected.size(); ++n) {
    const int i = named.selected[n];
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
      const double norms = jac.col(i).norm() * jac.col(k).norm();
      if (k == i || norms == 0) continue;
      const bool alternative = std::find(named.alternatives[n].begin(), named.alternatives[n].end(),
                                         k) != named.alternatives[n].end();
      if (alternative || std::abs(jac.col(i).dot(jac.col(k))) / norms >= options.equivalent_cosine)
        c.equivalent.push_back(paramName(k));
    }
    v.moved.push_back(std::move(c));
  }
  std::stable_sort(v.moved.begin(), v.moved.end(),
                   [](const ParameterChange& a, const ParameterChange& b) {
                     return a.significance > b.significance;
                   });
}

// Names what moved at the reference level, then at the check's own level when that is higher
// (the residual left after the named ones, per degree of freedom): a noisier day raises the
// level the changes are judged at, not the number of changes named.
void nameWhatMoved(const Model& active, const std::vector<Sample>& samples,
                   const HealthOptions& options, HealthVerdict& v) {
  const auto ownLevel = [&](const Named& n) {
    const double dof = static_cast<double>(samples.size()) - static_cast<double>(n.selected.size());
    return dof > 0 ? n.rms_mm * std::sqrt(static_cast<double>(samples.size()) / dof) : n.rms_mm;
  };
  double noise = v.reference_rms_mm;
  Named named = selectMoved(active, samples, options, noise, options.significance);
  for (int pass = 0; pass < 3 && ownLevel(named) > noise * 1.001; ++pass) {
    noise = ownLevel(named);
    // A level estimated from the check's own few dozen residuals is itself uncertain (13 % at
    // 30): judged at it, the same significance named something on 22 of 1,000 unchanged robots
    // read 1.5 times as noisy, and Student's t with the check's degrees of freedom on 5
    // (docs/health-check.md).
    const double dof =
        static_cast<double>(samples.size()) - static_cast<double>(named.selected.size());
    named =
        selectMoved(active, samples, options, noise, studentEquivalent(options.significance, dof));
  }
  v.noise_mm = noise;
  v.check_level_mm = ownLevel(named);
  v.refit_rms_mm = named.rms_mm;
  describeMoved(active, options, named, noise, v);
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

bool hasParamCovariance(const Model& m) {
  return m.covariance && m.covariance->cols() == m.covariance->rows() &&
         (m.covariance->rows() == kParamCount || (hasTwistRows(*m.covariance) && m.compliance));
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

  v.model_covariance = hasParamCovariance(active);
  nameWhatMoved(active, check_samples, options, v);
  v.refit_ratio = v.refit_rms_mm / v.reference_rms_mm;

  const std::string level =
      fmt("RMS %.4f mm is %.2f times ", v.residuals.rms_mm, v.rms_ratio) +
      (v.reference == HealthReference::kBaseline      ? "the baseline check's RMS"
       : v.reference == HealthReference::kCalibration ? "the calibration's fit RMS"
                                                      : "the fallback reference") +
      fmt(" of %.4f mm", v.reference_rms_mm);
  std::string moved;
  for (const ParameterChange& c : v.moved)
    moved += (moved.empty() ? "" : ", ") + c.text + fmt(" (%.1f sigma)", c.significance);
  // A check noisier than the calibration (its own level above the reference) sees less.
  const double noise_ratio = v.noise_mm / v.reference_rms_mm;
  const std::string noisier =
      noise_ratio >= 1.2 ? fmt("; the readings were %.2f times noisier than the reference, so "
                               "smaller changes could go unseen",
                               noise_ratio)
                         : std::string();
  if (static_cast<int>(v.samples) < options.min_samples) {
    v.status = HealthStatus::kWarn;
    v.reason =
        fmt("%.0f samples are too few to judge (at least %.0f): ", static_cast<double>(v.samples),
            options.min_samples) +
        level;
  } else if (!v.moved.empty()) {
    v.status = HealthStatus::kFail;
    v.reason = "the robot moved: " + moved + "; " + level +
               ": the model no longer fits the robot; recalibrate";
  } else if (v.rms_ratio >= options.fail_ratio) {
    v.status = HealthStatus::kFail;
    v.reason = level + fmt(", at or above %.2f, and no few parameters explain it: the model no "
                           "longer fits the robot (or the bar is not seated: check it first); "
                           "recalibrate",
                           options.fail_ratio);
  } else if (v.rms_ratio >= options.warn_ratio) {
    v.status = HealthStatus::kWarn;
    v.reason = level + fmt(", at or above %.2f (fail from %.2f), and nothing the check can name "
                           "moved: noisier readings or a change spread over many parameters; "
                           "check the bar's seating and the chucks, and run the check again",
                           options.warn_ratio, options.fail_ratio);
  } else {
    v.status = HealthStatus::kPass;
    v.reason = "nothing the check can name moved; " + level +
               fmt(", below %.2f: the model still fits the robot", options.warn_ratio) + noisier;
  }
  return v;
}

}  // namespace robocal
