// robocal-bench-solver: times robocal's Levenberg-Marquardt (solveCalibration) on simulated
// ball-bar data sets and, when they are available, Ceres (DENSE_QR, LEVENBERG_MARQUARDT) and
// Eigen's unsupported LevenbergMarquardt (MINPACK lmder) on the same problem: same samples, same
// start (the nominal model), the same analytic residuals and Jacobian code (BarLengthModel, which
// evaluateProblem uses), and the same
// 36 free parameters (the redundant ones that robocal's solve found are held at their nominal
// values). Single thread. Documented in docs/performance.md.
//
// usage: robocal-bench-solver [options]
//   --repeats N          solves per case, median reported [7, 7, 5, 3 by case size]
//   --quick              leave out the 80,000-sample case
//   --only-small         only the two ~800-sample cases
//   --only-robocal       robocal's solver alone (for profiling it with perf or callgrind)
//   --seed S             seed of the truth, poses and noise, as robocal simulate [1]
//   --initial-lambda L   robocal's starting damping (relative to the diagonal of the scaled
//                        J^T J) and Ceres' initial trust region radius 1/L [1e-6, the default]
// robocal is timed twice per repeat: a whole solve ("robocal"), and a refit of the same plan
// whose identifiability analysis comes from an IdentifiabilityCache ("robocal refit").
#include <robocal/kinematics/kinematics.hpp>
#include <robocal/robot/puma560.hpp>
#include <robocal/sim/measurements.hpp>
#include <robocal/solver/calibrate.hpp>
#include <robocal/solver/identifiability.hpp>
#include <robocal/solver/problem.hpp>

#ifdef ROBOCAL_BENCH_HAVE_CERES
#include <ceres/ceres.h>
#endif
#ifdef ROBOCAL_BENCH_HAVE_EIGEN_LM
#include <unsupported/Eigen/NonLinearOptimization>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace robocal;
using Clock = std::chrono::steady_clock;

constexpr double kNoiseMm = 0.084;
// Final costs of two solvers "agree" when they differ by less than this, relative.
constexpr double kCostAgreement = 1e-9;

// robocal's SolveOptions for every solve; Ceres and Eigen take their tolerances from it.
SolveOptions g_options;

double seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// CPU time of this thread: unlike the wall time, not inflated when other processes take the CPU.
double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

struct Stopwatch {
  Clock::time_point wall0 = Clock::now();
  double cpu0 = threadCpuSeconds();
  double wall() const { return seconds(wall0, Clock::now()); }
  double cpu() const { return threadCpuSeconds() - cpu0; }
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct DataSet {
  std::string name;
  int points_per_shell = 0;
  int shells = 0;
  Model nominal, truth;
  std::vector<Sample> samples;
  double make_seconds = 0;
};

// As `robocal simulate --seed S --connections ... --points-per-shell N` does it: the nominal
// PUMA 560, a truth perturbed with the default sigmas, poses found with the nominal model, lengths
// of the truth plus Gaussian noise of 0.084 mm.
DataSet makeDataSet(const std::string& name, const std::vector<Connection>& connections,
                    int points_per_shell, long seed) {
  const auto t0 = Clock::now();
  DataSet d;
  d.name = name;
  d.points_per_shell = points_per_shell;
  d.shells = static_cast<int>(connections.size());
  d.nominal = puma560NominalModel();
  std::mt19937_64 truth_rng(seed), pose_rng(seed * 7919 + 1), noise_rng(seed * 104729 + 2);
  d.truth = perturbModel(d.nominal, PerturbationSigmas{}, truth_rng);
  MeasurementNoise noise;
  noise.length_sigma_mm = kNoiseMm;
  int shell = 1;
  for (const Connection& c : connections) {
    ShellRequest req;
    req.connection = c;
    req.radius_mm = kDefaultBarMm;
    req.points = points_per_shell;
    req.shell = shell++;
    const ShellPoses poses = shellPoses(d.nominal, req, pose_rng);
    const auto s = measureShell(d.truth, req, poses.poses, noise, noise_rng);
    d.samples.insert(d.samples.end(), s.begin(), s.end());
  }
  d.make_seconds = seconds(t0, Clock::now());
  return d;
}

double costOf(const DataSet& d, const ParamVector& params) {
  Eigen::VectorXd r;
  evaluateProblem(d.nominal, params, d.samples, r, nullptr);
  return 0.5 * r.squaredNorm();
}

// One solver's result on one data set: the solves are deterministic, so only the time varies
// between repeats.
struct Outcome {
  explicit Outcome(std::string name) : solver(std::move(name)) {}
  std::string solver;
  std::vector<double> walls;  // seconds, one per repeat
  std::vector<double> cpus;   // thread CPU seconds, one per repeat
  int steps = 0;              // linear solves = trial steps, accepted or not
  double cost = 0;            // 0.5 sum r^2 at the solution (mm^2), recomputed the same way
  std::string stop;
  double wall() const { return median(walls); }
  double cpu() const { return median(cpus); }
  void record(const Stopwatch& w) {
    walls.push_back(w.wall());
    cpus.push_back(w.cpu());
  }
};

// ---------------------------------------------------------------------------------------------
// robocal: the whole solveCalibration call (identifiability analysis, iterations, covariance,
// observability statistics).

SolveResult runOurs(const DataSet& d, Outcome& out, IdentifiabilityCache* cache = nullptr) {
  SolveOptions options = g_options;
  options.identifiability_cache = cache;
  const Stopwatch watch;
  SolveResult result = solveCalibration(d.nominal, d.samples, options);
  out.record(watch);
  out.steps = result.iterations;
  out.cost = costOf(d, result.params);
  out.stop = stopReasonText(result.stop);
  return result;
}

// ---------------------------------------------------------------------------------------------
// Ceres: one SizedCostFunction<1, 54> per sample on one 54-parameter block, the redundant
// parameters held by a SubsetManifold. The BarLengthModel of the current point (per-link
// constants) is built once per evaluation point by an EvaluationCallback, as evaluateProblem
// builds it once per evaluation, so Ceres does not pay for it per sample.
#ifdef ROBOCAL_BENCH_HAVE_CERES

class ModelAtPoint : public ceres::EvaluationCallback {
 public:
  ModelAtPoint(const Model& fixtures, const double* params)
      : fixtures_(fixtures), params_(params), model_(fixtures, ParamVector(Map(params))) {}
  void PrepareForEvaluation(bool /*evaluate_jacobians*/, bool new_evaluation_point) override {
    if (new_evaluation_point) model_ = BarLengthModel(fixtures_, ParamVector(Map(params_)));
  }
  const BarLengthModel& model() const { return model_; }

 private:
  using Map = Eigen::Map<const ParamVector>;
  const Model& fixtures_;
  const double* params_;
  BarLengthModel model_;
};

// The same per-sample evaluation as evaluateProblem (BarLengthModel), one sample per block.
class BarLengthCost : public ceres::SizedCostFunction<1, kParamCount> {
 public:
  BarLengthCost(const ModelAtPoint& at, const Sample& s) : at_(at), sample_(s) {}
  bool Evaluate(double const* const* /*parameters*/, double* residuals,
                double** jacobians) const override {
    const BarLengthModel& model = at_.model();
    if (jacobians && jacobians[0]) {
      residuals[0] = sample_.length_mm - model.lengthGradient(sample_, jacobians[0]);
      for (int i = 0; i < kParamCount; ++i) jacobians[0][i] = -jacobians[0][i];
    } else {
      residuals[0] = sample_.length_mm - model.length(sample_);
    }
    return true;
  }

 private:
  const ModelAtPoint& at_;
  const Sample& sample_;
};

void runCeres(const DataSet& d, const std::vector<int>& redundant, Outcome& out) {
  const Stopwatch watch;
  ParamVector params = toParams(d.nominal);
  ModelAtPoint at(d.nominal, params.data());
  ceres::Problem::Options problem_options;
  problem_options.evaluation_callback = &at;
  ceres::Problem problem(problem_options);
  for (const Sample& s : d.samples)
    problem.AddResidualBlock(new BarLengthCost(at, s), nullptr, params.data());
  if (!redundant.empty())
    problem.SetManifold(params.data(), new ceres::SubsetManifold(kParamCount, redundant));

  ceres::Solver::Options options;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.linear_solver_type = ceres::DENSE_QR;
  options.num_threads = 1;
  options.max_num_iterations = g_options.max_iterations;
  options.function_tolerance = g_options.cost_change_tol;
  options.parameter_tolerance = g_options.step_tol;
  options.gradient_tolerance = g_options.gradient_tol;
  options.initial_trust_region_radius = 1.0 / g_options.initial_lambda;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  out.record(watch);
  out.steps = summary.num_successful_steps + summary.num_unsuccessful_steps;
  out.cost = costOf(d, params);
  out.stop = std::string(ceres::TerminationTypeToString(summary.termination_type)) + ": " +
             summary.message;
}
#endif

// ---------------------------------------------------------------------------------------------
// Eigen unsupported LevenbergMarquardt (a port of MINPACK lmder: QR with column pivoting of the
// m x n Jacobian each iteration, More's trust region) on the free parameters only.
#ifdef ROBOCAL_BENCH_HAVE_EIGEN_LM

struct FreeParamsFunctor {
  const DataSet* data = nullptr;
  ParamVector base;
  std::vector<int> free;
  mutable Eigen::MatrixXd full_jacobian;
  mutable Eigen::VectorXd scratch;

  int inputs() const { return static_cast<int>(free.size()); }
  int values() const { return static_cast<int>(data->samples.size()); }
  ParamVector expand(const Eigen::VectorXd& x) const {
    ParamVector p = base;
    for (size_t k = 0; k < free.size(); ++k) p[free[k]] = x[static_cast<Eigen::Index>(k)];
    return p;
  }
  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& fvec) const {
    evaluateProblem(data->nominal, expand(x), data->samples, fvec, nullptr);
    return 0;
  }
  int df(const Eigen::VectorXd& x, Eigen::MatrixXd& fjac) const {
    evaluateProblem(data->nominal, expand(x), data->samples, scratch, &full_jacobian);
    for (size_t k = 0; k < free.size(); ++k)
      fjac.col(static_cast<Eigen::Index>(k)) = full_jacobian.col(free[k]);
    return 0;
  }
};

const char* eigenLmStatusText(int status) {
  switch (status) {
    case Eigen::LevenbergMarquardtSpace::RelativeReductionTooSmall:
      return "relative reduction (ftol)";
    case Eigen::LevenbergMarquardtSpace::RelativeErrorTooSmall:
      return "relative error (xtol)";
    case Eigen::LevenbergMarquardtSpace::RelativeErrorAndReductionTooSmall:
      return "relative reduction and error (ftol, xtol)";
    case Eigen::LevenbergMarquardtSpace::CosinusTooSmall:
      return "gradient (gtol)";
    case Eigen::LevenbergMarquardtSpace::TooManyFunctionEvaluation:
      return "function evaluation limit";
    case Eigen::LevenbergMarquardtSpace::FtolTooSmall:
    case Eigen::LevenbergMarquardtSpace::XtolTooSmall:
    case Eigen::LevenbergMarquardtSpace::GtolTooSmall:
      return "tolerance too small (machine precision)";
    default:
      return "other";
  }
}

void runEigenLm(const DataSet& d, const std::vector<int>& free, Outcome& out) {
  const Stopwatch watch;
  FreeParamsFunctor f;
  f.data = &d;
  f.base = toParams(d.nominal);
  f.free = free;
  Eigen::VectorXd x(static_cast<Eigen::Index>(free.size()));
  for (size_t k = 0; k < free.size(); ++k) x[static_cast<Eigen::Index>(k)] = f.base[free[k]];
  Eigen::LevenbergMarquardt<FreeParamsFunctor> lm(f);
  lm.parameters.ftol = g_options.cost_change_tol;
  lm.parameters.xtol = g_options.step_tol;
  lm.parameters.gtol = 0;
  lm.parameters.maxfev = g_options.max_iterations + 1;
  const int status = lm.minimize(x);
  out.record(watch);
  out.steps = static_cast<int>(lm.nfev) - 1;
  out.cost = costOf(d, f.expand(x));
  out.stop = eigenLmStatusText(status);
}
#endif

// ---------------------------------------------------------------------------------------------

struct CaseResult {
  const DataSet* data = nullptr;
  SolveResult ours_result;
  double jacobian_eval_seconds = 0;  // one evaluateProblem with the Jacobian, median
  std::vector<Outcome> outcomes;     // ours first
};

bool g_only_robocal = false;

CaseResult runCase(const DataSet& d, int repeats) {
  CaseResult c;
  c.data = &d;
  Outcome ours("robocal");
  // A refit of the same plan: the identifiability analysis comes from a cache that an untimed
  // solve filled (what repeated centring refits or a re-measured plan get).
  Outcome refit("robocal refit");
  IdentifiabilityCache cache;
#ifdef ROBOCAL_BENCH_HAVE_CERES
  Outcome ceres_out("Ceres DENSE_QR");
#endif
#ifdef ROBOCAL_BENCH_HAVE_EIGEN_LM
  Outcome eigen_out("Eigen LM");
#endif
  // Interleaved, so a slow patch of the machine hits all solvers alike.
  for (int i = 0; i < repeats; ++i) {
    c.ours_result = runOurs(d, ours);
    if (i == 0) {
      SolveOptions fill = g_options;
      fill.identifiability_cache = &cache;
      solveCalibration(d.nominal, d.samples, fill);
    }
    runOurs(d, refit, &cache);
    const auto& redundant = c.ours_result.identifiability.redundant;
    const auto& free = c.ours_result.free_params;
    if (g_only_robocal) continue;
#ifdef ROBOCAL_BENCH_HAVE_CERES
    runCeres(d, redundant, ceres_out);
#endif
#ifdef ROBOCAL_BENCH_HAVE_EIGEN_LM
    runEigenLm(d, free, eigen_out);
#endif
    (void)redundant;
    (void)free;
  }
  c.outcomes.push_back(ours);
  c.outcomes.push_back(refit);
  if (g_only_robocal) return c;
#ifdef ROBOCAL_BENCH_HAVE_CERES
  c.outcomes.push_back(ceres_out);
#endif
#ifdef ROBOCAL_BENCH_HAVE_EIGEN_LM
  c.outcomes.push_back(eigen_out);
#endif
  // What one residual-and-Jacobian evaluation costs on its own (the part that must be linear).
  std::vector<double> evals;
  Eigen::VectorXd r;
  Eigen::MatrixXd j;
  for (int i = 0; i < std::max(3, repeats); ++i) {
    const auto t0 = Clock::now();
    evaluateProblem(d.nominal, toParams(d.nominal), d.samples, r, &j);
    evals.push_back(seconds(t0, Clock::now()));
  }
  c.jacobian_eval_seconds = median(evals);
  return c;
}

void printCase(const CaseResult& c) {
  const DataSet& d = *c.data;
  const size_t m = d.samples.size();
  const SolveResult& r = c.ours_result;
  const double expected_rms = kNoiseMm * std::sqrt(double(m - 36) / double(m));
  std::printf(
      "\n== %s: %zu samples (%d shells, %d points wanted per shell; made in %.2f s), %zu "
      "repeats\n",
      d.name.c_str(), m, d.shells, d.points_per_shell, d.make_seconds, c.outcomes[0].walls.size());
  std::printf(
      "   rank %d, %zu free parameters; RMS %.4f -> %.4f mm (noise-floor %.4f mm, ratio %.3f)\n",
      r.identifiability.rank, r.free_params.size(), r.before.rms_mm, r.after.rms_mm, expected_rms,
      r.after.rms_mm / expected_rms);
  std::printf("   one residual+Jacobian evaluation: %.3f ms (%.3f us/sample)\n",
              1e3 * c.jacobian_eval_seconds, 1e6 * c.jacobian_eval_seconds / double(m));
  const Outcome& ours = c.outcomes[0];
  for (const Outcome& o : c.outcomes) {
    const double wall = o.wall();
    const auto [lo, hi] = std::minmax_element(o.walls.begin(), o.walls.end());
    std::printf(
        "   %-15s wall %9.3f ms (min %.3f, max %.3f), cpu %9.3f ms; steps %3d, %8.3f ms/step, "
        "%7.3f us/sample; cost %.9g mm^2\n",
        o.solver.c_str(), 1e3 * wall, 1e3 * *lo, 1e3 * *hi, 1e3 * o.cpu(), o.steps,
        o.steps ? 1e3 * wall / o.steps : 0.0, 1e6 * wall / double(m), o.cost);
    if (&o != &ours) {
      const double rel = std::abs(o.cost - ours.cost) / ours.cost;
      std::printf("      %s / robocal: wall %.2fx, cpu %.2fx; final cost %s (rel diff %.1e)\n",
                  o.solver.c_str(), wall / ours.wall(), o.cpu() / ours.cpu(),
                  rel <= kCostAgreement ? "agrees" : "DIFFERS", rel);
    }
    std::printf("      stop: %s\n", o.stop.c_str());
  }
}

// The summary table in Markdown, for docs/performance.md.
bool printTable(const std::vector<CaseResult>& cases) {
  bool all_agree = true;
  std::printf(
      "\n| case | samples | solver | wall ms | cpu ms | steps | ms/step | us/sample | final cost "
      "(mm^2) | wall vs robocal | cpu vs robocal |\n"
      "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const CaseResult& c : cases) {
    const size_t m = c.data->samples.size();
    const Outcome& ours = c.outcomes[0];
    for (const Outcome& o : c.outcomes) {
      const double wall = o.wall();
      const bool agree = std::abs(o.cost - ours.cost) <= kCostAgreement * ours.cost;
      all_agree = all_agree && agree;
      std::printf("| %s | %zu | %s | %.2f | %.2f | %d | %.3f | %.2f | %.6f%s | %.2fx | %.2fx |\n",
                  c.data->name.c_str(), m, o.solver.c_str(), 1e3 * wall, 1e3 * o.cpu(), o.steps,
                  o.steps ? 1e3 * wall / o.steps : 0.0, 1e6 * wall / double(m), o.cost,
                  agree ? "" : " (differs)", wall / ours.wall(), o.cpu() / ours.cpu());
    }
  }
  return all_agree;
}

std::string cpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(colon + 2);
    }
  return "unknown";
}

}  // namespace

int main(int argc, char** argv) {
  int repeats_override = 0;
  bool quick = false, only_small = false;
  long seed = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--repeats" && i + 1 < argc) {
      repeats_override = std::atoi(argv[++i]);
    } else if (a == "--initial-lambda" && i + 1 < argc) {
      g_options.initial_lambda = std::atof(argv[++i]);
      if (!(g_options.initial_lambda > 0)) {
        std::fprintf(stderr, "--initial-lambda must be positive\n");
        return 2;
      }
    } else if (a == "--only-robocal") {
      g_only_robocal = true;
    } else if (a == "--quick") {
      quick = true;
    } else if (a == "--only-small") {
      only_small = true;
    } else if (a == "--seed" && i + 1 < argc) {
      seed = std::atol(argv[++i]);
    } else {
      std::fprintf(stderr,
                   "usage: robocal-bench-solver [--repeats N] [--quick] [--seed S] "
                   "[--initial-lambda L] [--only-robocal] [--only-small]\n");
      return a == "--help" ? 0 : 2;
    }
  }

  std::printf(
      "robocal-bench-solver: CPU %s, single thread; noise %.3f mm, seed %ld; initial lambda %g\n",
      cpuModel().c_str(), kNoiseMm, seed, g_options.initial_lambda);
#ifdef ROBOCAL_BENCH_HAVE_CERES
  std::printf("comparing with Ceres %s (DENSE_QR, LEVENBERG_MARQUARDT, num_threads 1)\n",
              CERES_VERSION_STRING);
#else
  std::printf("Ceres not found at build time: no Ceres comparison\n");
#endif
#ifdef ROBOCAL_BENCH_HAVE_EIGEN_LM
  std::printf("comparing with Eigen %d.%d.%d unsupported LevenbergMarquardt (MINPACK lmder)\n",
              EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION);
#endif

  const std::vector<Connection> nine = allConnections();
  const std::vector<Connection> seven = parseConnections("B1C1,B1C2,B1C3,B2C1,B2C2,B3C1,B3C3");
  struct Spec {
    std::string name;
    std::vector<Connection> connections;
    int points;
    int repeats;
  };
  std::vector<Spec> specs = {{"9 shells ~800", nine, 89, 7},
                             {"7 shells ~800", seven, 115, 7},
                             {"9 shells ~8000", nine, 889, 5}};
  if (only_small) specs.pop_back();
  if (!quick && !only_small) specs.push_back({"9 shells ~80000", nine, 8889, 3});

  std::vector<DataSet> data;
  data.reserve(specs.size());
  std::vector<CaseResult> cases;
  for (const Spec& s : specs) {
    data.push_back(makeDataSet(s.name, s.connections, s.points, seed));
    cases.push_back(runCase(data.back(), repeats_override > 0 ? repeats_override : s.repeats));
    printCase(cases.back());
    std::fflush(stdout);
  }
  const bool agree = printTable(cases);

  // The speed targets: time per sample flat from ~800 to ~80,000 samples, for the whole
  // solve and for the refit.
  const auto perSample = [&](size_t k, size_t o, bool cpu) {
    const Outcome& out = cases[k].outcomes[o];
    return (cpu ? out.cpu() : out.wall()) / double(data[k].samples.size());
  };
  for (size_t o = 0; o < 2; ++o)
    for (size_t k = 1; k < cases.size(); ++k)
      if (data[k].shells == data[0].shells)
        std::printf("\n%s time per sample, %s vs %s: wall %.2fx, cpu %.2fx (1.00 = flat)",
                    cases[0].outcomes[o].solver.c_str(), data[k].name.c_str(), data[0].name.c_str(),
                    perSample(k, o, false) / perSample(0, o, false),
                    perSample(k, o, true) / perSample(0, o, true));
  std::printf("\n");
  // The targets at ~800 samples: 3x Ceres DENSE_QR and 1.5x Eigen LM, for the whole
  // solve (analysis included) and for a refit of the same plan (analysis cached).
  if (!g_only_robocal) {
    const auto target = [&](const char* peer, double factor) {
      for (const Outcome& o : cases[0].outcomes) {
        if (o.solver != peer) continue;
        for (size_t k = 0; k < 2; ++k) {
          const Outcome& ours = cases[0].outcomes[k];
          const double ratio = o.wall() / ours.wall();
          std::printf(
              "target at ~800 samples (%s), %s at least %.1fx faster than %s: wall %.2fx, "
              "cpu %.2fx: %s\n",
              data[0].name.c_str(), ours.solver.c_str(), factor, peer, ratio, o.cpu() / ours.cpu(),
              ratio >= factor ? "met" : "NOT met");
        }
      }
    };
    target("Ceres DENSE_QR", 3.0);
    target("Eigen LM", 1.5);
  }
  std::printf("final costs %s\n",
              agree ? "agree between the solvers" : "DIFFER between the solvers (see the table)");
  return agree ? 0 : 1;
}
