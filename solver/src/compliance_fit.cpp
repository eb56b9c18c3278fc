#include <robocal/solver/compliance_fit.hpp>

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/twist.hpp>
#include <robocal/solver/adequacy.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace robocal {
namespace {

// Each sample's gravity torque (N m) at the start model's rigid pose.
std::vector<std::array<double, kJointCount>> torques(const Model& start,
                                                     const std::vector<Sample>& samples) {
  const RigidGravityTorque torque_nm(start);
  std::vector<std::array<double, kJointCount>> out;
  out.reserve(samples.size());
  for (const Sample& s : samples) out.push_back(torque_nm(s.joints_deg));
  return out;
}

std::array<double, kJointCount> rmsTorques(const std::vector<std::array<double, kJointCount>>& t) {
  std::array<double, kJointCount> rms{};
  for (const auto& row : t)
    for (int j = 0; j < kJointCount; ++j) rms[j] += row[j] * row[j];
  for (double& r : rms) r = std::sqrt(r / std::max<std::size_t>(1, t.size()));
  return rms;
}

}  // namespace

std::string ComplianceEstimate::summary() const {
  if (joints.empty()) return "no joint carries the arm's weight at these poses: none identified";
  std::string out;
  char buf[256];
  for (int j : joints) {
    std::snprintf(buf, sizeof buf, "%sjoint %d %.3g +/- %.2g", out.empty() ? "" : ", ", j + 1,
                  fitted_deg_per_nm[j], sigma_deg_per_nm[j]);
    out += buf;
  }
  std::snprintf(buf, sizeof buf, " deg/(N m): up to %.3f +/- %.3f deg of twist at these poses",
                largest_twist_deg, largest_twist_sigma_deg);
  out += buf;
  if (identified) return out;
  std::snprintf(
      buf, sizeof buf,
      "; not told from noise (chi-square %.1f, needs %.1f): the model stays rigid. A plan "
      "designed for it (robocal plan --compliance) on chucks placed apart would show it "
      "(docs/accuracy.md, \"Chucks placed apart\")",
      chi2, chi2_threshold);
  return out + buf;
}

std::vector<int> loadedJoints(const Model& start, const std::vector<Sample>& samples) {
  if (!start.compliance) return {};
  return loadedJoints(rmsTorques(torques(start, samples)));
}

std::vector<int> loadedJoints(const std::array<double, kJointCount>& rms) {
  const double largest = *std::max_element(rms.begin(), rms.end());
  std::vector<int> joints;
  for (int j = 0; j < kJointCount; ++j)
    if (largest > 0 && rms[j] >= 0.1 * largest) joints.push_back(j);
  return joints;
}

SolveResult solveWithCompliance(const Model& start, const std::vector<Sample>& samples,
                                const SolveOptions& options, ComplianceEstimate& out) {
  if (!start.compliance)
    throw std::invalid_argument(
        "the model has no compliance load (link masses, the fixture): add a \"compliance\" object "
        "(docs/model-format.md)");
  out = {};
  const auto tau = torques(start, samples);
  const auto rms = rmsTorques(tau);
  out.joints = loadedJoints(rms);
  Model model = start;
  const auto fitAt = [&](const std::array<double, kJointCount>& twist) {
    model.compliance->deg_per_nm = twist;
    ++out.fits;
    return solveCalibration(model, samples, options);
  };
  std::array<double, kJointCount> twist = start.compliance->deg_per_nm;
  const Eigen::Index m = static_cast<Eigen::Index>(samples.size());
  const Eigen::Index k = static_cast<Eigen::Index>(out.joints.size());
  SolveResult fit = fitAt(twist);
  const SolveResult at_start = fit;  // kept when the twist is not told from noise
  Eigen::MatrixXd jac(m, k);
  // What a twist moves the fitted parameters by (ParamVector units per deg/(N m)).
  Eigen::MatrixXd absorbed(kParamCount, k);
  if (k > 0) {
    // The Jacobian of the fitted residuals by differences, each step a 1e-3 deg RMS twist.
    for (Eigen::Index c = 0; c < k; ++c) {
      const int j = out.joints[c];
      const double step = 1e-3 / rms[j];
      std::array<double, kJointCount> moved = twist;
      moved[j] += step;
      const SolveResult at_moved = fitAt(moved);
      jac.col(c) = (at_moved.residuals - fit.residuals) / step;
      absorbed.col(c) = (at_moved.params - fit.params) / step;
    }
    // Two Gauss-Newton steps on it (the residual is nearly linear in the twist).
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(jac);
    for (int step = 0; step < 2; ++step) {
      const Eigen::VectorXd delta = qr.solve(-fit.residuals);
      for (Eigen::Index c = 0; c < k; ++c) twist[out.joints[c]] += delta[c];
      fit = fitAt(twist);
    }
    const Eigen::MatrixXd cov =
        fit.sigma_mm * fit.sigma_mm *
        (jac.transpose() * jac).ldlt().solve(Eigen::MatrixXd::Identity(k, k));
    Eigen::VectorXd change(k);
    for (Eigen::Index c = 0; c < k; ++c) {
      out.sigma_deg_per_nm[out.joints[c]] = std::sqrt(std::max(0.0, cov(c, c)));
      change[c] = twist[out.joints[c]] - start.compliance->deg_per_nm[out.joints[c]];
    }
    out.chi2 = change.dot(cov.ldlt().solve(change));
    out.chi2_threshold = chi2Quantile(static_cast<int>(k), 1e-3);
    // Kept when it stands out of its uncertainty and is a twist a model file holds (|c| <= 0.1).
    out.identified =
        out.chi2 > out.chi2_threshold &&
        std::all_of(twist.begin(), twist.end(), [](double c) { return std::abs(c) <= 0.1; });
    // The joint covariance (the header): the 54's own at the twist the model takes (the fitted
    // one when kept, the start's when not), and the twist's carried into them by what it moves
    // them. Kept or not, the twist is known only to its uncertainty.
    const int n = kParamCount;
    out.covariance =
        Eigen::MatrixXd::Zero(twistCovarianceIndex(kJointCount), twistCovarianceIndex(kJointCount));
    const Eigen::MatrixXd moved = absorbed * cov;  // Cov(params, twist)
    out.covariance.topLeftCorner(n, n) =
        (out.identified ? fit : at_start).covariance + moved * absorbed.transpose();
    for (Eigen::Index a = 0; a < k; ++a) {
      const int ja = twistCovarianceIndex(out.joints[a]);
      out.covariance.block(0, ja, n, 1) = moved.col(a);
      out.covariance.block(ja, 0, 1, n) = moved.col(a).transpose();
      for (Eigen::Index b = 0; b < k; ++b)
        out.covariance(ja, twistCovarianceIndex(out.joints[b])) = cov(a, b);
    }
    // The largest twist over the samples and its sigma (the twist's gradient in c is the torque).
    for (const auto& t : tau) {
      double twist_deg = 0;
      Eigen::VectorXd g(k);
      for (Eigen::Index c = 0; c < k; ++c) {
        g[c] = t[out.joints[c]];
        twist_deg += twist[out.joints[c]] * g[c];
      }
      if (std::abs(twist_deg) > std::abs(out.largest_twist_deg)) {
        out.largest_twist_deg = twist_deg;
        out.largest_twist_sigma_deg = std::sqrt(std::max(0.0, g.dot(cov * g)));
      }
    }
  }
  out.compliance = *start.compliance;
  out.compliance.deg_per_nm = out.fitted_deg_per_nm = twist;
  if (k > 0 && !out.identified) {  // not told from noise: the start's twist, and its fit
    out.compliance.deg_per_nm = start.compliance->deg_per_nm;
    return at_start;
  }

  fit.before = at_start.before;  // the start's, with the start's twist
  return fit;
}

}  // namespace robocal
