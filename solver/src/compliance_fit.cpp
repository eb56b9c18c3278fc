#include <robocal/solver/compliance_fit.hpp>

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/twist.hpp>
#include <robocal/solver/adequacy.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
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

// Each joint's largest gravity torque (N m, absolute) over joint vectors drawn within the limits:
// what a twist per N m means at the worst pose of the arm's range.
std::array<double, kJointCount> largestTorquesNm(const Model& start) {
  const RigidGravityTorque torque_nm(start);
  std::mt19937_64 rng(1);
  std::array<double, kJointCount> largest{};
  JointsDeg q;
  for (int n = 0; n < 2000; ++n) {
    for (int j = 0; j < kJointCount; ++j)
      q[j] = std::uniform_real_distribution<double>(start.joints[j].min_deg,
                                                    start.joints[j].max_deg)(rng);
    const auto t = torque_nm(q);
    for (int j = 0; j < kJointCount; ++j) largest[j] = std::max(largest[j], std::abs(t[j]));
  }
  return largest;
}

}  // namespace

std::array<double, kJointCount> priorTwistSigmaDegPerNm(const Model& start) {
  std::array<double, kJointCount> sigma{};
  if (!start.compliance) return sigma;
  const auto largest = largestTorquesNm(start);
  for (int j = 0; j < kJointCount; ++j)
    sigma[j] = largest[j] > 1e-9 ? kPriorLargestTwistDeg / largest[j] : 0;
  return sigma;
}

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
      "; not told from noise (chi-square %.1f, needs %.1f): the model stays rigid, and its "
      "predictions count the twist it may have. Chucks placed about 600 mm apart (the "
      "reference cell's) would show it (docs/accuracy.md, \"The whole range by default\")",
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
    // What the predictions count: a twist told from noise, the data's uncertainty; one not told,
    // that bounded by what a twist can be (priorTwistSigmaDegPerNm, as a Gaussian prior): where
    // the data barely tell it (one shell, the paper's compact fixture), about the prior's size
    // instead of a sigma far past any real arm's.
    // The model keeps the start's twist, so what the data and the prior together say it is
    // (the posterior's mean) counts as an error beside their uncertainty.
    Eigen::MatrixXd counted = cov;
    if (!out.identified) {
      const auto prior = priorTwistSigmaDegPerNm(start);
      const Eigen::MatrixXd data_information =
          jac.transpose() * jac / (fit.sigma_mm * fit.sigma_mm);
      Eigen::MatrixXd information = data_information;
      for (Eigen::Index c = 0; c < k; ++c) {
        const double p = prior[out.joints[c]];
        if (p > 0) information(c, c) += 1 / (p * p);
      }
      counted = information.ldlt().solve(Eigen::MatrixXd::Identity(k, k));
      const Eigen::VectorXd posterior_change = counted * (data_information * change);
      counted += posterior_change * posterior_change.transpose();
      for (Eigen::Index c = 0; c < k; ++c)
        out.sigma_deg_per_nm[out.joints[c]] = std::sqrt(std::max(0.0, counted(c, c)));
    }
    // The joint covariance (the header): the 54's own at the twist the model takes (the fitted
    // one when kept, the start's when not), and the twist's carried into them by what it moves
    // them. Kept or not, the twist is known only to its uncertainty.
    const int n = kParamCount;
    out.covariance =
        Eigen::MatrixXd::Zero(twistCovarianceIndex(kJointCount), twistCovarianceIndex(kJointCount));
    const Eigen::MatrixXd moved = absorbed * counted;  // Cov(params, twist)
    out.covariance.topLeftCorner(n, n) =
        (out.identified ? fit : at_start).covariance + moved * absorbed.transpose();
    for (Eigen::Index a = 0; a < k; ++a) {
      const int ja = twistCovarianceIndex(out.joints[a]);
      out.covariance.block(0, ja, n, 1) = moved.col(a);
      out.covariance.block(ja, 0, 1, n) = moved.col(a).transpose();
      for (Eigen::Index b = 0; b < k; ++b)
        out.covariance(ja, twistCovarianceIndex(out.joints[b])) = counted(a, b);
    }
    // A joint whose twist was not looked for (its torque too small at these poses: the wrist's)
    // may twist where the arm's whole range loads it: as compliant per N m as the most compliant
    // joint measured (the twist the model takes, or its uncertainty), independent of the rest.
    double measured = 0;
    for (Eigen::Index c = 0; c < k; ++c) {
      const int j = out.joints[c];
      const double taken = out.identified ? twist[j] : start.compliance->deg_per_nm[j];
      measured = std::max({measured, std::abs(taken), std::sqrt(counted(c, c))});
    }
    for (int j = 0; j < kJointCount; ++j)
      if (std::find(out.joints.begin(), out.joints.end(), j) == out.joints.end())
        out.covariance(twistCovarianceIndex(j), twistCovarianceIndex(j)) = measured * measured;
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
        out.largest_twist_sigma_deg = std::sqrt(std::max(0.0, g.dot(counted * g)));
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
