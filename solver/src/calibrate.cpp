#include <robocal/solver/calibrate.hpp>

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/solver/problem.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace robocal {
namespace {

void checkSamples(const std::vector<Sample>& samples) {
  if (samples.empty()) throw std::invalid_argument("no samples to fit");
  for (const Sample& s : samples)
    if (s.ball_index < 0 || s.ball_index >= kBallCount || s.chuck_index < 0 ||
        s.chuck_index >= kChuckCount)
      throw std::invalid_argument("sample at " + s.source + ":" + std::to_string(s.source_line) +
                                  " names a ball or chuck that does not exist");
}

double median(std::vector<double> v) {
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  return v[mid];
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace

const char* stopReasonText(StopReason reason) {
  switch (reason) {
    case StopReason::kCostChange:
      return "relative cost change below tolerance";
    case StopReason::kStepSize:
      return "step size below tolerance";
    case StopReason::kGradient:
      return "gradient below tolerance";
    case StopReason::kMaxIterations:
      return "iteration limit reached";
    case StopReason::kNoProgress:
      return "no step lowers the cost (damping exhausted)";
  }
  return "?";
}

ResidualStats residualStats(const Eigen::VectorXd& r) {
  ResidualStats s;
  s.count = static_cast<size_t>(r.size());
  if (r.size() == 0) return s;
  s.rms_mm = std::sqrt(r.squaredNorm() / r.size());
  s.mean_mm = r.mean();
  s.max_abs_mm = r.cwiseAbs().maxCoeff();
  return s;
}

const Identifiability* IdentifiabilityCache::find(const Model& start,
                                                  const std::vector<Sample>& samples) {
  if (!valid_ || samples.size() != poses_.size() || toParams(start) != params_) return nullptr;
  for (int b = 0; b < kBallCount; ++b)
    if (start.balls_mm[b] != balls_mm_[b]) return nullptr;
  for (int c = 0; c < kChuckCount; ++c)
    if (start.chucks_mm[c] != chucks_mm_[c]) return nullptr;
  for (size_t i = 0; i < samples.size(); ++i) {
    const Sample& s = samples[i];
    const Pose& p = poses_[i];
    if (s.ball_index != p.ball_index || s.chuck_index != p.chuck_index ||
        s.joints_deg != p.joints_deg)
      return nullptr;
  }
  ++hits_;
  return &analysis_;
}

void IdentifiabilityCache::store(const Model& start, const std::vector<Sample>& samples,
                                 Identifiability analysis) {
  params_ = toParams(start);
  balls_mm_ = start.balls_mm;
  chucks_mm_ = start.chucks_mm;
  poses_.clear();
  poses_.reserve(samples.size());
  for (const Sample& s : samples) poses_.push_back({s.joints_deg, s.ball_index, s.chuck_index});
  analysis_ = std::move(analysis);
  valid_ = true;
  ++misses_;
}

void IdentifiabilityCache::clear() {
  valid_ = false;
  poses_.clear();
  analysis_ = Identifiability{};
}

SolveResult solveCalibration(const Model& start, const std::vector<Sample>& samples,
                             const SolveOptions& opt) {
  checkSamples(samples);
  const Eigen::Index m = static_cast<Eigen::Index>(samples.size());
  const bool prior = opt.prior_sigma.has_value();
  if (prior && !(opt.prior_sigma->array() > 0).all())
    throw std::invalid_argument("prior sigmas must all be positive");
  const ParamVector start_params = toParams(start);
  const Eigen::Index rows = m + (prior ? kParamCount : 0);

  // Allocation up front. The residuals and the Jacobian are evaluated together at every trial
  // point: from a sensible start nearly every step is accepted, and the accepted trial's
  // Jacobian is the next step's, so each step costs one pass over the samples, not two.
  Eigen::MatrixXd jac(rows, kParamCount), trial_jac(rows, kParamCount);
  Eigen::VectorXd residuals(rows), trial_residuals(rows);
  Eigen::MatrixXd sample_jac;
  Eigen::VectorXd sample_residuals;
  ParamVector params = start_params;

  // Residuals and Jacobian of the samples, then of the prior rows.
  auto evaluate = [&](const ParamVector& p, Eigen::VectorXd& r, Eigen::MatrixXd& j) {
    if (!prior) {
      evaluateProblem(start, p, samples, r, &j);
      return;
    }
    evaluateProblem(start, p, samples, sample_residuals, &sample_jac);
    r.head(m) = sample_residuals;
    r.tail(kParamCount) = (start_params - p).cwiseQuotient(*opt.prior_sigma);
    j.topRows(m) = sample_jac;
    j.bottomRows(kParamCount) = (-opt.prior_sigma->cwiseInverse()).asDiagonal();
  };

  SolveResult result;
  evaluate(params, residuals, jac);
  result.before = residualStats(residuals.head(m));
  // The analysis depends on the start point and the poses only: a cache may hold it.
  IdentifiabilityCache* cache = opt.identifiability_cache;
  if (const Identifiability* cached = cache ? cache->find(start, samples) : nullptr) {
    result.identifiability = *cached;
  } else {
    result.identifiability = analyzeIdentifiability(prior ? Eigen::MatrixXd(jac.topRows(m)) : jac);
    if (cache) cache->store(start, samples, result.identifiability);
  }
  // With a prior every parameter is estimated; without, the identifiable basis.
  std::vector<int> candidates = result.identifiability.identified;
  if (prior) {
    candidates.resize(kParamCount);
    std::iota(candidates.begin(), candidates.end(), 0);
  }
  for (int i : candidates)
    if (std::find(opt.fixed.begin(), opt.fixed.end(), i) == opt.fixed.end())
      result.free_params.push_back(i);
  const auto& free = result.free_params;
  const Eigen::Index r = static_cast<Eigen::Index>(free.size());

  // Scaled variables x_k = scale_k * p_free[k] give the free Jacobian columns unit norm.
  Eigen::VectorXd scale(r);
  for (Eigen::Index k = 0; k < r; ++k) scale[k] = jac.col(free[k]).norm();
  Eigen::MatrixXd free_jac(rows, r), a(r, r), damped(r, r);
  Eigen::VectorXd g(r), step(r), x(r);
  Eigen::LDLT<Eigen::MatrixXd> ldlt(r), undamped(r);

  // a = J_s^T J_s and g = J_s^T r on the scaled free columns only (the fixed columns never enter
  // a step): one symmetric rank-m update of r x r instead of 54 x 54.
  auto normalEquations = [&]() {
    for (Eigen::Index k = 0; k < r; ++k) free_jac.col(k) = jac.col(free[k]) / scale[k];
    a.setZero();
    a.selfadjointView<Eigen::Lower>().rankUpdate(free_jac.transpose());
    a.triangularView<Eigen::StrictlyUpper>() = a.transpose();
    g.noalias() = free_jac.transpose() * residuals;
    undamped.compute(a);
  };

  double cost = 0.5 * residuals.squaredNorm();
  double lambda = opt.initial_lambda, nu = 2.0;
  result.stop = StopReason::kMaxIterations;
  bool have_normal_equations = false;
  while (r > 0) {
    if (!have_normal_equations) {
      normalEquations();
      have_normal_equations = true;
      // The most any step can gain, to second order, is the Gauss-Newton step's predicted
      // decrease 0.5 g^T a^-1 g. When that is below the cost-change tolerance the point is the
      // minimum: stop without spending a trial evaluation that could only be rejected by
      // rounding or accepted for nothing.
      if (undamped.info() == Eigen::Success && undamped.isPositive()) {
        const double gain = 0.5 * g.dot(undamped.solve(g));
        if (std::isfinite(gain) && gain >= 0 && gain <= opt.cost_change_tol * cost) {
          result.stop = StopReason::kCostChange;
          break;
        }
      }
    }
    // g = J_s^T r with unit columns: max |g| / |r| is the largest cosine between r and a column.
    if (g.cwiseAbs().maxCoeff() <= opt.gradient_tol * std::sqrt(2 * cost)) {
      result.stop = StopReason::kGradient;
      break;
    }
    if (result.iterations >= opt.max_iterations) break;
    damped = a;
    damped.diagonal() += lambda * a.diagonal();
    ldlt.compute(damped);
    // r = measured - model, J = dr/dp: the Gauss-Newton step solves (J^T J) dx = -J^T r.
    step = ldlt.solve(-g);
    ++result.iterations;

    ParamVector trial = params;
    for (Eigen::Index k = 0; k < r; ++k) trial[free[k]] += step[k] / scale[k];
    evaluate(trial, trial_residuals, trial_jac);
    const double trial_cost = 0.5 * trial_residuals.squaredNorm();
    const double predicted = -(g.dot(step) + 0.5 * step.dot(a * step));
    const double rho = (cost - trial_cost) / predicted;

    if (std::isfinite(trial_cost) && predicted > 0 && rho > 0) {
      for (Eigen::Index k = 0; k < r; ++k) x[k] = params[free[k]] * scale[k];
      const double step_norm = step.norm();
      const double decrease = cost - trial_cost;
      params = trial;
      cost = trial_cost;
      residuals.swap(trial_residuals);
      jac.swap(trial_jac);
      lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
      nu = 2.0;
      have_normal_equations = false;
      if (decrease <= opt.cost_change_tol * (cost + decrease)) {
        result.stop = StopReason::kCostChange;
        break;
      }
      if (step_norm <= opt.step_tol * (x.norm() + opt.step_tol)) {
        result.stop = StopReason::kStepSize;
        break;
      }
    } else {
      // Near the minimum rounding rejects steps that could only gain less than the tolerance:
      // the cost-change test applies to rejected steps too.
      if (predicted >= 0 && predicted <= opt.cost_change_tol * cost) {
        result.stop = StopReason::kCostChange;
        break;
      }
      lambda *= nu;
      nu *= 2.0;
      if (lambda > 1e16) {
        result.stop = StopReason::kNoProgress;
        break;
      }
    }
  }

  result.params = params;
  result.residuals = residuals.head(m);
  result.after = residualStats(result.residuals);
  const Eigen::Index dof = std::max<Eigen::Index>(1, m - (prior ? 0 : r));
  result.sigma_mm = std::sqrt(result.residuals.squaredNorm() / dof);

  // Statistics at the solution, on the scaled free columns (the normal matrix of the last
  // accepted point, formed already unless the loop ended right after accepting it).
  result.covariance = Eigen::MatrixXd::Zero(kParamCount, kParamCount);
  if (r > 0) {
    if (!have_normal_equations) normalEquations();
    // Singular values of the scaled free Jacobian from the eigenvalues of its normal matrix:
    // accurate enough at these condition numbers (~1e3, i.e. 1e6 for A) and far cheaper than
    // another QR and SVD.
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(a, Eigen::EigenvaluesOnly);
    const Eigen::VectorXd sv = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().reverse();
    result.o3 = sv[r - 1];
    result.condition_number = sv[r - 1] > 0 ? sv[0] / sv[r - 1] : INFINITY;
    result.o1 = std::exp(sv.array().log().mean()) / std::sqrt(static_cast<double>(rows));
    const Eigen::MatrixXd inv = undamped.solve(Eigen::MatrixXd::Identity(r, r));
    const double var = result.sigma_mm * result.sigma_mm;
    for (Eigen::Index i = 0; i < r; ++i)
      for (Eigen::Index k = 0; k < r; ++k)
        result.covariance(free[i], free[k]) = var * inv(i, k) / (scale[i] * scale[k]);
  }
  return result;
}

Eigen::VectorXd sampleResiduals(const Model& model, const std::vector<Sample>& samples) {
  checkSamples(samples);
  Eigen::VectorXd r;
  evaluateProblem(model, toParams(model), samples, r, nullptr);
  return r;
}

std::vector<double> predictedBallErrors(const Model& model, const Eigen::MatrixXd& covariance,
                                        const std::vector<Sample>& samples) {
  const Kinematics kin(model);
  std::vector<double> out;
  out.reserve(samples.size());
  PositionJacobian g;
  for (const Sample& s : samples) {
    kin.ballPositionJacobian(s.joints_deg, model.balls_mm[s.ball_index], g);
    out.push_back(std::sqrt(std::max(0.0, (g * covariance * g.transpose()).trace())));
  }
  return out;
}

double barToEndpointErrorFactor(const Model& model, const std::vector<Sample>& samples) {
  const Kinematics kin(model);
  double sum = 0;
  size_t count = 0;
  for (const Sample& s : samples) {
    const Eigen::Isometry3d tool = kin.toolPose(s.joints_deg);
    const Eigen::Vector3d origin = tool.translation();
    Eigen::Matrix<double, kBallCount * kChuckCount, 6> legs;
    for (int b = 0; b < kBallCount; ++b)
      for (int c = 0; c < kChuckCount; ++c) {
        const Eigen::Vector3d ball = tool * model.balls_mm[b];
        const Eigen::Vector3d u = (ball - model.chucks_mm[c]).normalized();
        legs.block<1, 3>(b * kChuckCount + c, 0) = u.transpose();
        legs.block<1, 3>(b * kChuckCount + c, 3) = (ball - origin).cross(u).transpose();
      }
    const Eigen::Matrix<double, 6, 6> cov =
        (legs.transpose() * legs).ldlt().solve(Eigen::Matrix<double, 6, 6>::Identity());
    for (int b = 0; b < kBallCount; ++b) {
      Eigen::Matrix<double, 3, 6> move;
      move << Eigen::Matrix3d::Identity(), -skew(tool * model.balls_mm[b] - origin);
      sum += std::sqrt((move * cov * move.transpose()).trace());
      ++count;
    }
  }
  return count ? sum / count : 0.0;
}

std::vector<Outlier> findOutliers(const Eigen::VectorXd& residuals, double k) {
  std::vector<Outlier> out;
  if (residuals.size() < 3) return out;
  const std::vector<double> r(residuals.data(), residuals.data() + residuals.size());
  const double med = median(r);
  std::vector<double> dev(r.size());
  for (size_t i = 0; i < r.size(); ++i) dev[i] = std::abs(r[i] - med);
  const double robust_sigma = 1.4826 * median(dev);
  if (!(robust_sigma > 0)) return out;
  for (size_t i = 0; i < r.size(); ++i)
    if (dev[i] > k * robust_sigma) out.push_back({i, r[i], dev[i] / robust_sigma});
  return out;
}

}  // namespace robocal

namespace robocal {

TruthComparison compareWithTruth(const Model& nominal, const Model& calibrated, const Model& truth,
                                 const std::vector<Sample>& samples) {
  const Kinematics nominal_kin(nominal), calibrated_kin(calibrated), truth_kin(truth);
  TruthComparison out;
  double nominal_sum = 0, calibrated_sum = 0;
  for (const Sample& s : samples) {
    const Eigen::Vector3d& ball = truth.balls_mm[s.ball_index];
    const Eigen::Vector3d p = truth_kin.ballPosition(s.joints_deg, ball);
    nominal_sum += (nominal_kin.ballPosition(s.joints_deg, ball) - p).squaredNorm();
    const double e = (calibrated_kin.ballPosition(s.joints_deg, ball) - p).norm();
    calibrated_sum += e * e;
    out.calibrated_max_mm = std::max(out.calibrated_max_mm, e);
    ++out.poses;
  }
  if (out.poses) {
    out.nominal_rms_mm = std::sqrt(nominal_sum / out.poses);
    out.calibrated_rms_mm = std::sqrt(calibrated_sum / out.poses);
  }
  return out;
}

}  // namespace robocal
