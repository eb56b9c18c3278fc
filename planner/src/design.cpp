#include <robocal/planner/design.hpp>

#include "parallel.hpp"

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/twist.hpp>
#include <robocal/solver/compliance_fit.hpp>
#include <robocal/solver/identifiability.hpp>
#include <robocal/solver/problem.hpp>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace robocal {
namespace {

using detail::parallelFor;

// One shell the design may use, with its candidates as rows.
struct ShellPool {
  Connection connection;
  double extension_mm = 0;
  ShellCandidates candidates;
  Eigen::MatrixXd rows;  // one scaled row per candidate point (transposed: r x n)
};

// The chosen set and the inverse of its information, kept up to date by rank-one updates.
class Selection {
 public:
  Selection(const WorkVolumeCriterion& criterion, const Eigen::MatrixXd& prior)
      : criterion_(criterion), information_(prior) {
    refresh();
  }

  // How much adding each column j of `rows` would lower trace(M^-1 W):
  // (j^T M^-1 W M^-1 j) / (1 + j^T M^-1 j), for all columns with two matrix products.
  Eigen::VectorXd gainsOfAdding(const Eigen::MatrixXd& rows) const {
    const Eigen::MatrixXd u = inverse_ * rows;
    const Eigen::MatrixXd wu = criterion_.weight() * u;
    return (u.cwiseProduct(wu).colwise().sum().array() /
            (1.0 + rows.cwiseProduct(u).colwise().sum().array()))
        .transpose();
  }
  void add(const Eigen::VectorXd& j) { update(j, 1.0); }
  void remove(const Eigen::VectorXd& j) { update(j, -1.0); }
  double trace() const { return (inverse_ * criterion_.weight()).trace(); }
  const Eigen::MatrixXd& information() const { return information_; }

 private:
  void update(const Eigen::VectorXd& j, double sign) {
    information_.noalias() += sign * j * j.transpose();
    const Eigen::VectorXd u = inverse_ * j;
    const double d = 1.0 + sign * j.dot(u);
    if (++updates_ % 64 == 0 || d < 1e-9) {
      refresh();  // keep rounding from piling up
      return;
    }
    inverse_.noalias() -= (sign / d) * u * u.transpose();
  }
  void refresh() {
    const Eigen::LDLT<Eigen::MatrixXd> f(information_);
    inverse_ = f.solve(Eigen::MatrixXd::Identity(information_.rows(), information_.cols()));
  }
  const WorkVolumeCriterion& criterion_;
  Eigen::MatrixXd information_, inverse_;
  int updates_ = 0;
};

struct Pick {
  size_t shell, point;
};

}  // namespace

WorkVolumeCriterion::WorkVolumeCriterion(const Model& model, std::vector<int> identified,
                                         const std::vector<JointsDeg>& work_joints,
                                         const Eigen::Vector3d& tool_point_mm,
                                         double noise_sigma_mm,
                                         const std::vector<JointsDeg>& whole_range_joints,
                                         double whole_range_weight,
                                         std::vector<int> compliance_joints)
    : model_(model),
      identified_(std::move(identified)),
      compliance_joints_(std::move(compliance_joints)),
      sigma_(noise_sigma_mm) {
  if (work_joints.empty()) throw std::invalid_argument("work volume: no poses");
  if (!(noise_sigma_mm > 0)) throw std::invalid_argument("noise sigma must be > 0 mm");
  if (!(whole_range_weight >= 0)) throw std::invalid_argument("whole-range weight must be >= 0");
  if (!compliance_joints_.empty() && !model.compliance)
    throw std::invalid_argument("the model has no compliance load to design its twist for");
  const int r = size();
  const Kinematics kin(model);
  const auto jacobians = [&](const std::vector<JointsDeg>& joints) {
    std::vector<Eigen::MatrixXd> g(joints.size());
    PositionJacobian full;
    for (size_t k = 0; k < joints.size(); ++k) {
      kin.ballPositionJacobian(joints[k], tool_point_mm, full);
      g[k] = columns(full, joints[k]);
    }
    return g;
  };
  const std::vector<Eigen::MatrixXd> g = jacobians(work_joints);
  // Scale each parameter by its typical effect on the tool over the work volume, so that the
  // information matrix is well conditioned whatever the units (mm, rad, gain, deg/(N m)).
  scale_ = Eigen::VectorXd::Ones(r);
  for (int a = 0; a < r; ++a) {
    double sum = 0;
    for (const Eigen::MatrixXd& gk : g) sum += gk.col(a).squaredNorm();
    const double typical = std::sqrt(sum / g.size());
    if (typical > 1e-12) scale_[a] = 1.0 / typical;
  }
  // The mean of G_k^T G_k over poses, in the scaled parameters.
  const auto meanWeight = [&](const std::vector<Eigen::MatrixXd>& poses) {
    Eigen::MatrixXd w = Eigen::MatrixXd::Zero(r, r);
    for (const Eigen::MatrixXd& gk : poses) {
      const Eigen::MatrixXd scaled = gk * scale_.asDiagonal();
      w.noalias() += scaled.transpose() * scaled;
    }
    return Eigen::MatrixXd(w / static_cast<double>(poses.size()));
  };
  w_ = meanWeight(g);
  if (whole_range_weight > 0 && !whole_range_joints.empty())
    w_ += whole_range_weight * meanWeight(jacobians(whole_range_joints));
}

template <typename Full>
Eigen::MatrixXd WorkVolumeCriterion::columns(const Full& full, const JointsDeg& joints) const {
  Eigen::MatrixXd out(full.rows(), size());
  const int n = static_cast<int>(identified_.size());
  for (int a = 0; a < n; ++a) out.col(a) = full.col(identified_[a]);
  if (compliance_joints_.empty()) return out;
  const auto twist = twistColumns(full, RigidGravityTorque(model_)(joints));
  for (size_t c = 0; c < compliance_joints_.size(); ++c)
    out.col(n + static_cast<int>(c)) = twist.col(compliance_joints_[c]);
  return out;
}

Eigen::VectorXd WorkVolumeCriterion::row(const Connection& c, const JointsDeg& joints) const {
  ParamRow gradient;
  Kinematics(model_).barLengthGradient(joints, model_.balls_mm[c.ball_index],
                                       model_.chucks_mm[c.chuck_index], gradient);
  return columns(gradient, joints).row(0).transpose().cwiseProduct(scale_) / sigma_;
}

double WorkVolumeCriterion::predictedRms(const Eigen::MatrixXd& information) const {
  const Eigen::LDLT<Eigen::MatrixXd> f(information);
  if (f.info() != Eigen::Success || f.vectorD().minCoeff() <= 1e-12 * f.vectorD().maxCoeff())
    return std::numeric_limits<double>::infinity();
  return std::sqrt(std::max(0.0, (f.solve(w_)).trace()));
}

std::vector<int> identifiedParameters(const Model& model, const std::vector<Sample>& samples) {
  Eigen::VectorXd residuals;
  Eigen::MatrixXd jacobian;
  evaluateProblem(model, toParams(model), samples, residuals, &jacobian);
  Eigen::MatrixXd r = triangularFactor(jacobian);
  const int rank = analyzeIdentifiability(r).rank;
  // The `rank` best-conditioned columns (pivoted QR of the unit-norm columns). At a nominal
  // model they span what the solver's choice spans (the rest are exactly redundant), so the
  // tool's predicted error is the same; at a calibrated model, whose perturbed axes make some
  // redundant pairs barely distinguishable, they leave out the barely identified ones instead
  // of keeping them by the solver's fixed priority.
  for (int c = 0; c < r.cols(); ++c)
    if (r.col(c).norm() > 0) r.col(c).normalize();
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(r);
  std::vector<int> out;
  for (int k = 0; k < rank; ++k) out.push_back(qr.colsPermutation().indices()[k]);
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<int> designComplianceJoints(const Model& model, const std::vector<Sample>& samples,
                                        bool compliance) {
  if (!compliance) return {};
  if (!model.compliance)
    throw std::invalid_argument(
        "the model has no compliance load (link masses, the fixture) to plan its twist for: add "
        "a \"compliance\" object (docs/model-format.md)");
  return loadedJoints(model, samples);
}

double predictedWorkVolumeError(const Model& model, const Plan& plan,
                                const std::vector<JointsDeg>& work_joints, double noise_sigma_mm,
                                bool compliance) {
  const std::vector<Sample> samples = planSamples(model, plan);
  if (samples.empty()) return std::numeric_limits<double>::infinity();
  const WorkVolumeCriterion criterion(model, identifiedParameters(model, samples), work_joints,
                                      Eigen::Vector3d::Zero(), noise_sigma_mm, {}, 0,
                                      designComplianceJoints(model, samples, compliance));
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(criterion.size(), criterion.size());
  for (const ShellPlan& shell : plan.shells)
    for (const PlanStep& step : shell.steps)
      if (step.kind == StepKind::kPoint) {
        const Eigen::VectorXd j = criterion.row(shell.connection, step.joints_deg);
        m.noalias() += j * j.transpose();
      }
  return criterion.predictedRms(m);
}

std::vector<size_t> shortTour(const ShellPlanner& planner, const JointsDeg& start,
                              const std::vector<ShellPoint>& points) {
  const size_t n = points.size();
  std::vector<size_t> tour;
  if (n == 0) return tour;
  auto cost = [&](const JointsDeg& a, const JointsDeg& b) { return planner.moveDuration(a, b); };
  std::vector<char> used(n, 0);
  JointsDeg here = start;
  for (size_t step = 0; step < n; ++step) {
    size_t best = n;
    double best_cost = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < n; ++i)
      if (!used[i] && cost(here, points[i].joints_deg) < best_cost) {
        best_cost = cost(here, points[i].joints_deg);
        best = i;
      }
    used[best] = 1;
    tour.push_back(best);
    here = points[best].joints_deg;
  }
  // 2-opt on the open path from `start`: reverse tour[a..b] when that shortens it.
  auto at = [&](size_t k) -> const JointsDeg& { return points[tour[k]].joints_deg; };
  for (int pass = 0; pass < 20; ++pass) {
    bool improved = false;
    for (size_t a = 0; a + 1 < n; ++a)
      for (size_t b = a + 1; b < n; ++b) {
        const JointsDeg& before = a == 0 ? start : at(a - 1);
        const double old_cost = cost(before, at(a)) + (b + 1 < n ? cost(at(b), at(b + 1)) : 0.0);
        const double new_cost = cost(before, at(b)) + (b + 1 < n ? cost(at(a), at(b + 1)) : 0.0);
        if (new_cost < old_cost - 1e-9) {
          std::reverse(tour.begin() + a, tour.begin() + b + 1);
          improved = true;
        }
      }
    if (!improved) break;
  }
  return tour;
}

Plan joinChosenPoints(const Model& model, const ShellPlanner& planner,
                      const std::vector<ShellChoice>& shells) {
  Plan plan;
  plan.model_name = model.name;
  plan.cell = planner.cell();
  std::vector<size_t> used;
  for (size_t s = 0; s < shells.size(); ++s)
    if (std::find(shells[s].chosen.begin(), shells[s].chosen.end(), 1) != shells[s].chosen.end())
      used.push_back(s);
  plan.shells.resize(used.size());
  parallelFor(used.size(), [&](size_t n) {
    const ShellChoice& shell = shells[used[n]];
    const ShellCandidates& c = *shell.candidates;
    std::vector<ShellPoint> points;
    for (size_t i = 0; i < shell.chosen.size(); ++i)
      if (shell.chosen[i]) points.push_back(c.points[i]);
    const JointsDeg start = c.connect ? c.connect->joints_deg : points[0].joints_deg;
    std::vector<ShellPoint> ordered;
    for (size_t k : shortTour(planner, start, points)) ordered.push_back(points[k]);
    plan.shells[n] =
        planner.joinPoints(shell.connection, shell.extension_mm, static_cast<int>(n) + 1, c.config,
                           c.connect, std::move(ordered));
  });
  std::erase_if(plan.shells, [](const ShellPlan& s) { return s.summary.points == 0; });
  for (size_t n = 0; n < plan.shells.size(); ++n) plan.shells[n].shell = static_cast<int>(n) + 1;
  summarizePlan(plan);
  return plan;
}

namespace {

// The greedy pick and the exchange passes for one estimate of a point's cost in cell time.
std::vector<std::vector<char>> selectPoints(const ShellPlanner& planner,
                                            const std::vector<ShellPool>& pools,
                                            const WorkVolumeCriterion& criterion,
                                            const Eigen::MatrixXd& prior,
                                            const DesignOptions& options, double point_s,
                                            double swap_s, double budget_s) {
  Selection sel(criterion, prior);
  std::vector<std::vector<char>> chosen(pools.size());
  std::vector<int> per_shell(pools.size(), 0);
  for (size_t s = 0; s < pools.size(); ++s) chosen[s].assign(pools[s].rows.cols(), 0);
  int picked = 0, open_shells = 0;
  auto cellTime = [&] { return picked * point_s + open_shells * swap_s; };
  auto fits = [&](size_t shell) {
    if (options.points > 0 && picked >= options.points) return false;
    return budget_s <= 0 ||
           cellTime() + point_s + (per_shell[shell] == 0 ? swap_s : 0.0) <= budget_s;
  };
  // Motion: a candidate's move from the nearest point already chosen on its shell (from the
  // connect pose at first), so that the pick weighs information against travel. (Counting the
  // vias a long move needs, at one per 12 deg, gave no better plans on the reference cell.)
  const MotionSettings& motion = planner.cell().motion;
  const double dwell_s = motion.settle_s + motion.move_overhead_s;
  auto travel = [&](const JointsDeg& a, const JointsDeg& b) {
    return (b - a).cwiseAbs().maxCoeff() / motion.joint_speed_deg_per_s;
  };
  std::vector<std::vector<double>> travel_s(pools.size());
  for (size_t s = 0; s < pools.size(); ++s) {
    const ShellCandidates& c = pools[s].candidates;
    travel_s[s].resize(c.points.size());
    for (size_t i = 0; i < c.points.size(); ++i)
      travel_s[s][i] = c.connect ? travel(c.connect->joints_deg, c.points[i].joints_deg) : 0.0;
  }
  // A shell's first point pays for the swap, spread over the points a shell typically gets.
  // (3 points: measured on the reference cell, 15 and more open too many shells, 1 too few.)
  constexpr double kAmortisePoints = 3;
  while (true) {
    std::vector<std::pair<double, Pick>> scored;
    for (size_t s = 0; s < pools.size(); ++s) {
      if (!fits(s)) continue;
      const double swap = per_shell[s] == 0 ? swap_s / kAmortisePoints : 0.0;
      const Eigen::VectorXd gains = sel.gainsOfAdding(pools[s].rows);
      for (Eigen::Index i = 0; i < pools[s].rows.cols(); ++i)
        if (!chosen[s][i])
          scored.push_back({gains[i] / (dwell_s + travel_s[s][i] + swap), {s, size_t(i)}});
    }
    if (scored.empty()) break;
    // A few picks per scoring pass: the gains change little between them.
    const size_t batch = std::min(scored.size(), std::clamp<size_t>(picked / 20, 1, 8));
    std::partial_sort(scored.begin(), scored.begin() + batch, scored.end(),
                      [](const auto& a, const auto& b) { return a.first > b.first; });
    int added = 0;
    for (size_t b = 0; b < batch; ++b) {
      const Pick& p = scored[b].second;
      if (!fits(p.shell)) continue;
      chosen[p.shell][p.point] = 1;
      const std::vector<ShellPoint>& points = pools[p.shell].candidates.points;
      for (size_t i = 0; i < points.size(); ++i)
        travel_s[p.shell][i] = std::min(travel_s[p.shell][i],
                                        travel(points[p.point].joints_deg, points[i].joints_deg));
      open_shells += per_shell[p.shell]++ == 0;
      ++picked;
      ++added;
      sel.add(pools[p.shell].rows.col(p.point));
    }
    if (added == 0) break;
  }
  // Exchange: each chosen point against the best unchosen one of its shell (same cost).
  for (int pass = 0; pass < options.exchange_passes; ++pass) {
    int exchanges = 0;
    for (size_t s = 0; s < pools.size(); ++s)
      for (Eigen::Index i = 0; i < pools[s].rows.cols(); ++i) {
        if (!chosen[s][i]) continue;
        const double before = sel.trace();
        sel.remove(pools[s].rows.col(i));
        Eigen::Index best = i;
        const Eigen::VectorXd gains = sel.gainsOfAdding(pools[s].rows);
        double best_gain = gains[i];
        for (Eigen::Index k = 0; k < pools[s].rows.cols(); ++k)
          if (!chosen[s][k] && gains[k] > best_gain * (1 + 1e-9)) {
            best_gain = gains[k];
            best = k;
          }
        sel.add(pools[s].rows.col(best));
        if (best != i && sel.trace() < before) {
          chosen[s][i] = 0;
          chosen[s][best] = 1;
          ++exchanges;
        } else if (best != i) {
          sel.remove(pools[s].rows.col(best));
          sel.add(pools[s].rows.col(i));
        }
      }
    if (exchanges == 0) break;
  }
  return chosen;
}

}  // namespace

Plan planOptimal(const Model& model, const CellConfig& cell,
                 const std::vector<JointsDeg>& work_joints, const DesignOptions& options,
                 DesignReport* report) {
  if (options.budget_s <= 0 && options.points <= 0)
    throw PlanError("an optimal plan needs a time budget or a number of points");
  const ShellPlanner planner(model, cell);

  // Candidates on every shell the cell allows.
  std::vector<ShellPool> pools;
  for (double extension : cell.bar.extension_lengths_mm)
    for (const Connection& c : cell.connections) pools.push_back({c, extension, {}, {}});
  parallelFor(pools.size(), [&](size_t s) {
    pools[s].candidates = planner.candidatePoints(pools[s].connection, pools[s].extension_mm,
                                                  options.candidate_grid, options.orientations);
  });
  std::vector<Sample> all;
  for (const ShellPool& p : pools)
    for (const ShellPoint& pt : p.candidates.points)
      all.push_back(
          makeSample(0, p.connection, p.extension_mm, pt.lat_deg, pt.lon_deg, pt.joints_deg, 0));
  if (all.empty()) throw PlanError("no candidate point on any shell can be reached safely");
  const WorkVolumeCriterion criterion(model, identifiedParameters(model, all), work_joints,
                                      Eigen::Vector3d::Zero(), options.noise_sigma_mm,
                                      options.whole_range_joints, options.whole_range_weight,
                                      designComplianceJoints(model, all, options.compliance));
  const int r = criterion.size();
  parallelFor(pools.size(), [&](size_t s) {
    ShellPool& p = pools[s];
    p.rows.resize(r, static_cast<Eigen::Index>(p.candidates.points.size()));
    for (size_t i = 0; i < p.candidates.points.size(); ++i)
      p.rows.col(static_cast<Eigen::Index>(i)) =
          criterion.row(p.connection, p.candidates.points[i].joints_deg);
  });
  // A weak prior (a millionth of an average candidate's information per parameter) so that the
  // first picks have an objective to lower; the reported figures use the data alone.
  Eigen::MatrixXd prior = Eigen::MatrixXd::Zero(r, r);
  for (const ShellPool& p : pools) prior.diagonal() += p.rows.cwiseAbs2().rowwise().sum();
  prior.diagonal() *= 1e-6 / static_cast<double>(all.size());

  // Pick with an estimate of a point's cell time, plan the motion, measure, pick again.
  const MotionSettings& motion = cell.motion;
  double point_s = motion.settle_s + motion.move_overhead_s + 1.5;
  DesignReport rep;
  rep.candidates = static_cast<int>(all.size());
  Plan best;
  bool have_best = false;
  for (int round = 1; round <= 5; ++round) {
    rep.rounds = round;
    const auto chosen = selectPoints(planner, pools, criterion, prior, options, point_s,
                                     motion.swap_s, options.budget_s);
    std::vector<ShellChoice> choices;
    for (size_t p = 0; p < pools.size(); ++p)
      choices.push_back(
          {pools[p].connection, pools[p].extension_mm, &pools[p].candidates, chosen[p]});
    Plan plan = joinChosenPoints(model, planner, choices);
    if (plan.summary.points == 0) break;
    const double cell_s = plan.summary.cell_time_s;
    // The real cost of a point on this plan's tours (moves, vias, dwell), for the next pick;
    // a little more when over the budget, since fewer points lie further apart.
    const double real_point_s = plan.summary.duration_s / plan.summary.points;
    const bool fits = options.budget_s <= 0 || cell_s <= options.budget_s;
    // Keep the plan with the most points among those that fit (or the first, when none does).
    if (!have_best || (fits && (best.summary.cell_time_s > options.budget_s ||
                                plan.summary.points > best.summary.points))) {
      best = std::move(plan);
      have_best = true;
    }
    if (options.budget_s <= 0 || (fits && cell_s > 0.95 * options.budget_s)) break;
    point_s =
        std::max(real_point_s * (fits ? 1.0 : 1.05), motion.settle_s + motion.move_overhead_s);
  }
  if (!have_best) throw PlanError("no points fit the budget");
  summarizeIdentifiability(model, best);
  rep.predicted_cell_time_s = best.summary.cell_time_s;
  rep.predicted_rms_mm = predictedWorkVolumeError(model, best, work_joints, options.noise_sigma_mm,
                                                  options.compliance);
  if (report) *report = rep;
  return best;
}

}  // namespace robocal
