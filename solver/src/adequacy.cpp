#include <robocal/kinematics/kinematics.hpp>
#include <robocal/solver/adequacy.hpp>
#include <robocal/solver/problem.hpp>

#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

namespace robocal {
namespace {

bool sameShell(const Sample& a, const Sample& b) {
  return a.shell == b.shell && a.ball_index == b.ball_index && a.chuck_index == b.chuck_index &&
         a.extension_mm == b.extension_mm;
}

std::string joinJoints(const std::vector<int>& joints) {
  std::string out = joints.size() == 1 ? "joint " : "joints ";
  for (size_t i = 0; i < joints.size(); ++i) out += (i ? ", " : "") + std::to_string(joints[i] + 1);
  return out;
}

// An orthonormal basis of the Jacobian's column space: what the fit's parameters can explain.
Eigen::MatrixXd explainedBasis(const Eigen::MatrixXd& jacobian) {
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(jacobian);
  qr.setThreshold(1e-10);
  const Eigen::Index rank = qr.rank();
  const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(jacobian.rows(), rank);
  return q;
}

// The features' part the fit cannot explain: F minus its projection on the basis.
Eigen::MatrixXd unexplained(const Eigen::MatrixXd& features, const Eigen::MatrixXd& basis) {
  if (basis.cols() == 0) return features;
  return features - basis * (basis.transpose() * features);
}

struct Regression {
  double chi2 = 0;
  double rms_mm = 0;
};

// The residual regressed on the (unexplained) features.
Regression regress(const Eigen::MatrixXd& g, const Eigen::VectorXd& r, double sigma_mm) {
  Regression out;
  if (g.cols() == 0 || g.norm() == 0) return out;
  const Eigen::VectorXd beta = g.colPivHouseholderQr().solve(r);
  const Eigen::VectorXd fitted = g * beta;
  out.chi2 = fitted.dot(r) / (sigma_mm * sigma_mm);
  out.rms_mm = std::sqrt(fitted.squaredNorm() / static_cast<double>(r.size()));
  return out;
}

}  // namespace

// Upper quantiles of the chi-square distribution, at 1e-3 and 1e-2 (1 to 6 degrees of freedom).
double chi2Quantile(int dof, double false_alarm) {
  static constexpr double k1e3[] = {10.828, 13.816, 16.266, 18.467, 20.515, 22.458};
  static constexpr double k1e2[] = {6.635, 9.210, 11.345, 13.277, 15.086, 16.812};
  const int i = std::clamp(dof, 1, 6) - 1;
  return false_alarm <= 1e-3 ? k1e3[i] : k1e2[i];
}

namespace {

// The residuals of each place measured more than once (same shell, same lat/lon), about their
// mean: the bar's noise, whatever the model.
void measureNoise(const std::vector<Sample>& samples, const Eigen::VectorXd& residuals,
                  Adequacy& a) {
  std::map<SamplePlace, std::vector<double>> places;
  for (size_t i = 0; i < samples.size(); ++i)
    places[placeOf(samples[i])].push_back(residuals[static_cast<Eigen::Index>(i)]);
  double squares = 0;
  for (const auto& [place, r] : places) {
    if (r.size() < 2) continue;
    double mean = 0;
    for (double v : r) mean += v;
    mean /= static_cast<double>(r.size());
    for (double v : r) squares += (v - mean) * (v - mean);
    ++a.revisited_places;
    a.noise_dof += static_cast<int>(r.size()) - 1;
  }
  if (a.noise_dof > 0) a.noise_mm = std::sqrt(squares / a.noise_dof);
}

// The lower quantile of chi-square with `dof` degrees of freedom at 1e-3 or 1e-2
// (Wilson-Hilferty: within a few per cent from 10 degrees of freedom).
double chi2LowerQuantile(int dof, double false_alarm) {
  const double z = false_alarm <= 1e-3 ? -3.0902 : -2.3263;
  const double k = 2.0 / (9.0 * dof);
  return dof * std::pow(std::max(0.0, 1 - k + z * std::sqrt(k)), 3);
}

}  // namespace

std::string Adequacy::summary() const {
  char buf[200];
  std::string out;
  bool patterns_found = false;
  for (const AdequacyPattern& p : patterns) patterns_found = patterns_found || p.found;
  if (!patterns_found && !lack_of_fit) {
    std::snprintf(buf, sizeof buf, "no pattern in the residual (sigma %.3f mm)", sigma_mm);
    out = buf;
    if (noise_mm) {
      std::snprintf(buf, sizeof buf, "; the bar's noise measured by %d revisits: %.3f mm",
                    revisited_places, *noise_mm);
      out += buf;
    }
    if (drift.found) out += "; " + drift.summary();
    return out;
  }
  if (patterns_found) {
    // The same figure as lack_of_fit_mm and the model's unmodelled_mm.
    std::snprintf(buf, sizeof buf, "%.3f mm of error the model does not contain; it follows ",
                  unmodelled_bar_mm());
    out = buf;
    bool first = true;
    for (const AdequacyPattern& p : patterns) {
      if (!p.found) continue;
      out +=
          (first ? "the " : " and the ") + p.pattern + (p.detail.empty() ? "" : " of " + p.detail);
      first = false;
    }
  }
  if (lack_of_fit) {
    std::snprintf(buf, sizeof buf,
                  "%sthe fit's residual, %.3f mm, is %.2fx the bar's noise measured by %d "
                  "revisits (%.3f mm)",
                  out.empty() ? "" : "; ", sigma_mm, fit_over_noise, revisited_places,
                  noise_mm.value_or(0));
    out += buf;
    if (!patterns_found) {
      std::snprintf(buf, sizeof buf, ": %.3f mm of error the model does not contain",
                    unmodelled_bar_mm());
      out += buf;
    }
  }
  if (drift.found) out += "; " + drift.summary();
  return out;
}

double Adequacy::unmodelled_bar_mm() const {
  double mm = unmodelled_mm;
  if (lack_of_fit && noise_mm)
    mm = std::max(mm, std::sqrt(std::max(0.0, sigma_mm * sigma_mm - *noise_mm * *noise_mm)));
  return mm;
}

Adequacy testAdequacy(const Model& calibrated, const std::vector<Sample>& samples,
                      const Eigen::VectorXd& residuals, double sigma_mm, double false_alarm) {
  Adequacy a;
  a.sigma_mm = sigma_mm;
  const Eigen::Index n = static_cast<Eigen::Index>(samples.size());
  if (n < 20 || !(sigma_mm > 0) || residuals.size() != n) return a;
  Eigen::VectorXd unused;
  Eigen::MatrixXd jacobian;
  evaluateProblem(calibrated, toParams(calibrated), samples, unused, &jacobian);
  const Kinematics kin(calibrated);

  // The features, one block per pattern.
  Eigen::MatrixXd approach = Eigen::MatrixXd::Zero(n, kJointCount);
  Eigen::MatrixXd gravity = Eigen::MatrixXd::Zero(n, 2);
  Eigen::MatrixXd time = Eigen::MatrixXd::Zero(n, 1);
  // The place in the run, 0 to 1: by the samples' times when they all have one (a pause shows),
  // else by their order.
  const bool timed = std::all_of(samples.begin(), samples.end(),
                                 [](const Sample& s) { return s.time_s.has_value(); });
  double t_first = 0, t_last = 0;
  if (timed) {
    const auto [lo, hi] =
        std::minmax_element(samples.begin(), samples.end(),
                            [](const Sample& x, const Sample& y) { return *x.time_s < *y.time_s; });
    t_first = *lo->time_s;
    t_last = *hi->time_s;
  }
  auto runFraction = [&](Eigen::Index i) {
    if (timed && t_last > t_first)
      return (*samples[static_cast<size_t>(i)].time_s - t_first) / (t_last - t_first);
    return static_cast<double>(i) / static_cast<double>(n - 1);
  };
  for (Eigen::Index i = 0; i < n; ++i) {
    const Sample& s = samples[static_cast<size_t>(i)];
    if (i > 0 && sameShell(s, samples[static_cast<size_t>(i - 1)]))
      for (int j = 0; j < kJointCount; ++j) {
        const double step = s.joints_deg[j] - samples[static_cast<size_t>(i - 1)].joints_deg[j];
        if (std::abs(step) > 1e-9)
          approach(i, j) = jacobian(i, jointParamIndex(j)) * (step > 0 ? 1.0 : -1.0);
      }
    const auto frames = kin.chainFrames(s.joints_deg);
    const Eigen::Vector3d wrist_m = frames[2 * 4 + 1].translation() * 1e-3;
    for (int k = 0; k < 2; ++k) {
      const Eigen::Isometry3d& joint = frames[2 * (k + 1) + 1];
      const double torque = (wrist_m - joint.translation() * 1e-3)
                                .cross(-Eigen::Vector3d::UnitZ())
                                .dot(joint.linear().col(2));
      gravity(i, k) = jacobian(i, jointParamIndex(k + 1)) * torque;
    }
    double scale = 0;  // dL/d(growth of the link translations L1..L6)
    for (int k = 1; k < kLinkCount; ++k) {
      const LinkParams& l = calibrated.links[k];
      const int p = linkParamIndex(k);
      scale += jacobian(i, p) * l.x_mm + jacobian(i, p + 1) * l.y_mm + jacobian(i, p + 2) * l.z_mm;
    }
    time(i, 0) = scale * runFraction(i);
  }

  struct Block {
    const char* name;
    Eigen::MatrixXd features;
    int first_joint;  // joint of the first column, for the detail (-1: none)
  };
  const Eigen::MatrixXd basis = explainedBasis(jacobian);  // one QR for the three patterns
  std::vector<Block> blocks = {{"approach direction", unexplained(approach, basis), 0},
                               {"gravity torque", unexplained(gravity, basis), 1},
                               {"time", unexplained(time, basis), -1}};
  Eigen::MatrixXd found_features(n, 0);
  for (Block& b : blocks) {
    AdequacyPattern p;
    p.pattern = b.name;
    p.features = static_cast<int>(b.features.cols());
    p.threshold = chi2Quantile(p.features, false_alarm);
    const Regression all = regress(b.features, residuals, sigma_mm);
    p.chi2 = all.chi2;
    p.rms_mm = all.rms_mm;
    p.found = p.chi2 > p.threshold;
    if (p.found && b.first_joint >= 0) {
      std::vector<int> joints;
      for (Eigen::Index c = 0; c < b.features.cols(); ++c)
        if (regress(b.features.col(c), residuals, sigma_mm).chi2 > chi2Quantile(1, false_alarm))
          joints.push_back(b.first_joint + static_cast<int>(c));
      if (!joints.empty()) p.detail = joinJoints(joints);
    }
    if (p.found) {
      found_features.conservativeResize(n, found_features.cols() + b.features.cols());
      found_features.rightCols(b.features.cols()) = b.features;
    }
    a.patterns.push_back(p);
  }
  a.ok = found_features.cols() == 0;
  if (!a.ok) a.unmodelled_mm = regress(found_features, residuals, sigma_mm).rms_mm;

  measureNoise(samples, residuals, a);
  a.drift = measureDrift(samples, residuals, false_alarm);
  if (a.noise_mm && *a.noise_mm > 0 && a.noise_dof >= 10) {
    // sigma^2 / noise^2 is about 1 when the model is right; the noise's own estimate may be low
    // by chance, by chi2(dof)/dof at its lower quantile.
    a.fit_over_noise = sigma_mm / *a.noise_mm;
    a.fit_over_noise_limit = std::sqrt(a.noise_dof / chi2LowerQuantile(a.noise_dof, false_alarm));
    a.lack_of_fit = a.fit_over_noise > a.fit_over_noise_limit;
    if (a.lack_of_fit) a.ok = false;
  }
  return a;
}

}  // namespace robocal
