#include <robocal/solver/calibrate.hpp>

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/twist.hpp>
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
  if (!valid_ || samples.size() != poses_.size() || toParams(start) != params_ ||
      start.compliance != compliance_)
    return nullptr;
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
  compliance_ = start.compliance;
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

  // The residuals and the Jacobian are evaluated together at every trial point: from a sensible
  // start nearly every step is accepted, and the accepted trial's normal equations are the next
  // step's, so each step costs one pass over the samples, not two.
  Eigen::VectorXd residuals(rows), trial_residuals(rows);
  ParamVector params = start_params;

  // The unscaled normal equations n = J_c^T J_c (lower triangle) and b = J_c^T r on the columns
  // `cols`, accumulated over blocks of samples whose Jacobian rows stay in cache; row(i) gives
  // row i of J (and may compute it, and residual i, on the way). The prior rows are added last.
  constexpr Eigen::Index kBlock = 256;
  Eigen::MatrixXd block;  // one sample's Jacobian row (the columns `cols`) per column
  auto accumulate = [&](const std::vector<int>& cols, const Eigen::VectorXd& res,
                        Eigen::MatrixXd& n, Eigen::VectorXd& b, const auto& row) {
    const Eigen::Index c = static_cast<Eigen::Index>(cols.size());
    block.resize(c, kBlock);
    n.setZero(c, c);
    b.setZero(c);
    for (Eigen::Index s0 = 0; s0 < m; s0 += kBlock) {
      const Eigen::Index len = std::min(kBlock, m - s0);
      for (Eigen::Index i = 0; i < len; ++i) {
        const double* j = row(s0 + i);
        for (Eigen::Index k = 0; k < c; ++k) block(k, i) = j[cols[k]];
      }
      if (c == 0) continue;
      n.selfadjointView<Eigen::Lower>().rankUpdate(block.leftCols(len));
      b.noalias() += block.leftCols(len) * res.segment(s0, len);
    }
    if (prior) {
      // Prior row i: residual (start_i - p_i) / sigma_i, Jacobian -1 / sigma_i in column i.
      for (Eigen::Index k = 0; k < c; ++k) {
        const double w = 1.0 / (*opt.prior_sigma)[cols[k]];
        n(k, k) += w * w;
        b[k] -= w * res[m + cols[k]];
      }
    }
  };
  // One pass over the samples at p: the residuals and n, b on `cols`. The m x 54 Jacobian is not
  // stored, so the time per sample does not grow with m; `full` gets it when the identifiability
  // analysis needs it.
  ParamRow jac_row;
  auto pass = [&](const ParamVector& p, const std::vector<int>& cols, Eigen::VectorXd& res,
                  Eigen::MatrixXd& n, Eigen::VectorXd& b, Eigen::MatrixXd* full) {
    const BarLengthModel model(start, p);
    if (full) full->resize(m, kParamCount);
    if (prior) res.tail(kParamCount) = (start_params - p).cwiseQuotient(*opt.prior_sigma);
    accumulate(cols, res, n, b, [&](Eigen::Index i) {
      const Sample& s = samples[static_cast<size_t>(i)];
      res[i] = s.length_mm - model.lengthGradient(s, jac_row.data());
      jac_row = -jac_row;  // r = measured - length
      if (full) full->row(i) = jac_row;
      return jac_row.data();
    });
  };

  SolveResult result;
  // The analysis depends on the start point and the poses only: a cache may hold it. Without it,
  // the start pass keeps the Jacobian for the analysis and the normal equations are formed from
  // it afterwards, in the same blocks and order, so that both ways give the same numbers.
  IdentifiabilityCache* cache = opt.identifiability_cache;
  const Identifiability* cached = cache ? cache->find(start, samples) : nullptr;
  Eigen::MatrixXd n, trial_n, start_jac;
  Eigen::VectorXd b, trial_b;
  if (cached) {
    result.identifiability = *cached;
  } else {
    pass(params, {}, residuals, n, b, &start_jac);
    result.identifiability = analyzeIdentifiability(start_jac);
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
  if (cached) {
    pass(params, free, residuals, n, b, nullptr);
  } else {
    accumulate(free, residuals, n, b, [&](Eigen::Index i) {
      jac_row = start_jac.row(i);
      return jac_row.data();
    });
    start_jac.resize(0, 0);
  }
  result.before = residualStats(residuals.head(m));

  // Scaled variables x_k = scale_k * p_free[k] give the free Jacobian columns (at the start)
  // unit norm.
  Eigen::VectorXd scale(r);
  for (Eigen::Index k = 0; k < r; ++k) scale[k] = std::sqrt(n(k, k));
  Eigen::MatrixXd a(r, r), damped(r, r);
  Eigen::VectorXd g(r), step(r), x(r);
  Eigen::LDLT<Eigen::MatrixXd> ldlt(r), undamped(r);

  // a = J_s^T J_s and g = J_s^T r on the scaled free columns from a pass's n and b (the fixed
  // columns never enter a step).
  auto setNormalEquations = [&](const Eigen::MatrixXd& nn, const Eigen::VectorXd& bb) {
    for (Eigen::Index i = 0; i < r; ++i) {
      g[i] = bb[i] / scale[i];
      for (Eigen::Index k = 0; k <= i; ++k) a(i, k) = a(k, i) = nn(i, k) / (scale[i] * scale[k]);
    }
    undamped.compute(a);
  };
  if (r > 0) setNormalEquations(n, b);

  double cost = 0.5 * residuals.squaredNorm();
  double lambda = opt.initial_lambda, nu = 2.0;
  result.stop = StopReason::kMaxIterations;
  bool new_point = true;
  while (r > 0) {
    if (new_point) {
      new_point = false;
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
    pass(trial, free, trial_residuals, trial_n, trial_b, nullptr);
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
      setNormalEquations(trial_n, trial_b);
      new_point = true;
      lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
      nu = 2.0;
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
  // accepted point).
  result.covariance = Eigen::MatrixXd::Zero(kParamCount, kParamCount);
  if (r > 0) {
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
  Eigen::Matrix<double, 3, twistCovarianceIndex(kJointCount)> with_twist;
  const RigidGravityTorque torque_nm(model);
  for (const Sample& s : samples) {
    kin.ballPositionJacobian(s.joints_deg, model.balls_mm[s.ball_index], g);
    double variance = 0;
    if (hasTwistRows(covariance)) {  // the twists' columns after the 54's
      with_twist << g, twistColumns(g, torque_nm(s.joints_deg));
      variance = (with_twist * covariance * with_twist.transpose()).trace();
    } else {
      variance = (g * covariance * g.transpose()).trace();
    }
    out.push_back(std::sqrt(std::max(0.0, variance)));
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

TruthComparison compareWithTruth(const Model& nominal, const Model& calibrated,
                                 const TrueBallMm& true_ball_mm,
                                 const std::vector<Sample>& samples) {
  const Kinematics nominal_kin(nominal), calibrated_kin(calibrated);
  TruthComparison out;
  double nominal_sum = 0, calibrated_sum = 0;
  for (const Sample& s : samples) {
    const int b = s.ball_index;
    const Eigen::Vector3d p = true_ball_mm(s);
    nominal_sum += (nominal_kin.ballPosition(s.joints_deg, nominal.balls_mm[b]) - p).squaredNorm();
    const double e = (calibrated_kin.ballPosition(s.joints_deg, calibrated.balls_mm[b]) - p).norm();
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
