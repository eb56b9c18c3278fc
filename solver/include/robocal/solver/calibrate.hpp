// Identification of the kinematic parameters from ball-bar samples: a hand-written
// Levenberg-Marquardt on the identifiable subspace, then the statistics an engineer needs to trust
// the result (residuals, parameter covariance, predicted ball-position error, observability).
//
// The 54 parameters are not all identifiable (J^T J is singular). Before iterating, the
// column-scaled Jacobian at the start point is analysed (identifiability.hpp): the parameters of
// its priority basis are estimated and the redundant ones stay fixed at their starting (nominal)
// values, so no direction can wander. Columns are scaled to unit norm, which makes the damping
// and the stopping rules independent of units (mm, rad, gain).
#pragma once

#include <robocal/kinematics/model.hpp>
#include <robocal/kinematics/sample.hpp>
#include <robocal/solver/identifiability.hpp>

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace robocal {

// The identifiability analysis of a start point and a set of sample poses, kept across fits.
// solveCalibration analyses the column-scaled Jacobian at the start point (identifiability.hpp),
// a QR of the m x 54 Jacobian and an SVD: at ~800 samples that is as much work as the whole fit.
// The Jacobian at the start point depends only on the start model's 54 parameters, compliance,
// balls and chucks, and each sample's joint readings, ball and chuck, not on the measured lengths.
// A cache passed in SolveOptions reuses the analysis when all of these are exactly the same as in
// the fit that stored it (refits of the same poses with new lengths), and replaces it otherwise, so
// a stale analysis is never used. The result is then the same as without the cache. One entry; not
// thread-safe: one cache per thread of fits.
class IdentifiabilityCache {
 public:
  // The analysis stored for exactly this start point and these poses (counted as a hit), or null.
  const Identifiability* find(const Model& start, const std::vector<Sample>& samples);
  // Replaces the stored analysis (counted as a miss).
  void store(const Model& start, const std::vector<Sample>& samples, Identifiability analysis);
  void clear();
  int hits() const { return hits_; }      // fits that reused the stored analysis
  int misses() const { return misses_; }  // fits that had to analyse (and stored the result)

 private:
  struct Pose {
    JointsDeg joints_deg;
    int ball_index = 0, chuck_index = 0;
  };
  bool valid_ = false;
  ParamVector params_ = ParamVector::Zero();
  std::optional<JointCompliance> compliance_;
  std::array<Eigen::Vector3d, kBallCount> balls_mm_{};
  std::array<Eigen::Vector3d, kChuckCount> chucks_mm_{};
  std::vector<Pose> poses_;
  Identifiability analysis_;
  int hits_ = 0;
  int misses_ = 0;
};

struct SolveOptions {
  int max_iterations = 100;
  // Stop when a step lowers the cost by less than this (relative), or, before a trial, when the
  // Gauss-Newton step's predicted decrease 0.5 g^T (J^T J)^-1 g is below it: no step can gain more.
  double cost_change_tol = 1e-12;
  double step_tol = 1e-12;       // stop when the scaled step is this small relative to x
  double gradient_tol = 1e-12;   // stop when max |scaled gradient| / cost is below this
  double initial_lambda = 1e-6;  // damping, relative to the diagonal of the scaled J^T J
  // Parameters to hold fixed in addition to the redundant ones (indices into ParamVector).
  std::vector<int> fixed;
  // A prior: when set (all positive), each parameter also gets the residual
  // (start - p) / prior_sigma, so every parameter is estimated, pulled toward its start value
  // where the data say little. For fits of a few samples (keeping the bar centred while a shell
  // runs); the covariance then includes the prior.
  std::optional<ParamVector> prior_sigma;
  // When set, the identifiability analysis is taken from this cache if it holds the analysis of
  // the same start point and poses, and stored in it otherwise (IdentifiabilityCache above). Not
  // owned; must outlive the call.
  IdentifiabilityCache* identifiability_cache = nullptr;
};

enum class StopReason { kCostChange, kStepSize, kGradient, kMaxIterations, kNoProgress };
const char* stopReasonText(StopReason reason);

struct ResidualStats {
  size_t count = 0;
  double rms_mm = 0;
  double mean_mm = 0;
  double max_abs_mm = 0;
};
ResidualStats residualStats(const Eigen::VectorXd& residuals);

struct SolveResult {
  ParamVector params;               // the estimate; redundant parameters at their start values
  Identifiability identifiability;  // of the start point: rank, redundant set, singular values
  std::vector<int> free_params;     // the parameters that were estimated (sorted)
  int iterations = 0;               // trial steps evaluated (accepted or rejected)
  StopReason stop = StopReason::kMaxIterations;
  ResidualStats before, after;
  Eigen::VectorXd residuals;  // per sample at the solution, mm
  double sigma_mm = 0;        // residual standard error, sqrt(sum r^2 / (m - rank))
  // sigma^2 (J_f^T J_f)^-1 on the free parameters, zero rows/columns for fixed ones (ParamVector
  // units). Equal to sigma^2 (J^T J)^+ in the gauge where the redundant parameters are fixed.
  Eigen::MatrixXd covariance;
  double condition_number = 0;  // of the column-scaled Jacobian on the free parameters
  double o1 = 0;                // observability index O1: (prod sigma_i)^(1/r) / sqrt(m)
  double o3 = 0;                // observability index O3: smallest singular value
};

// Fits the model's 54 parameters (starting from `start`) to the samples. Throws
// std::invalid_argument when there are no samples or a sample names a ball or chuck that does not
// exist.
SolveResult solveCalibration(const Model& start, const std::vector<Sample>& samples,
                             const SolveOptions& options = {});

// Residuals of samples under a model (validation without refitting).
Eigen::VectorXd sampleResiduals(const Model& model, const std::vector<Sample>& samples);

// Predicted 1-sigma ball-position error (sqrt of the trace of the 3x3 covariance) of the
// calibrated model at each sample's pose, for the sample's ball; `covariance` of the 54, or of
// the 54 and the twists (Model::covariance).
std::vector<double> predictedBallErrors(const Model& model, const Eigen::MatrixXd& covariance,
                                        const std::vector<Sample>& samples);

// The paper's "bar error to endpoint error" factor: at each pose, the three balls as a Stewart
// platform measured by the nine bars with independent errors of one unit; returns the mean over
// the poses of the resulting 1-sigma ball-position error.
double barToEndpointErrorFactor(const Model& model, const std::vector<Sample>& samples);

struct Outlier {
  size_t index = 0;  // into the samples
  double residual_mm = 0;
  double robust_sigmas = 0;  // |r - median| / (1.4826 MAD)
};
// Samples whose residual is more than k robust standard deviations from the median.
std::vector<Outlier> findOutliers(const Eigen::VectorXd& residuals, double k);

}  // namespace robocal

namespace robocal {

// For simulations: how far the nominal and the calibrated models put the balls from where the
// true robot has them, at the samples' poses (each sample's own ball).
struct TruthComparison {
  size_t poses = 0;
  double nominal_rms_mm = 0;
  double calibrated_rms_mm = 0;
  double calibrated_max_mm = 0;
};
// Where the true robot puts a sample's ball (mm, global frame): its geometry and what a real arm
// adds (backlash, compliance, warm-up: sim/true_robot.hpp), so that a model is not judged against
// a truth without what the model was fitted to absorb.
using TrueBallMm = std::function<Eigen::Vector3d(const Sample&)>;
TruthComparison compareWithTruth(const Model& nominal, const Model& calibrated,
                                 const TrueBallMm& true_ball_mm,
                                 const std::vector<Sample>& samples);

}  // namespace robocal
