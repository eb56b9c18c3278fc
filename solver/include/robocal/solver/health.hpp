// The health check's verdict (docs/health-check.md): does the calibrated model in use still fit the
// robot? A short verification run (planner/health_plan.hpp: two connections, an extension the
// calibration did not use, 30 points chosen for detection) is predicted by the active model
// without refitting. A small refit from the active model, pulled toward it by a prior, names what
// moved: parameters are added one at a time, each the one whose change (prior-weighted) explains
// most of what is left, while that is significant at the noise level the check is judged at (the
// calibration's, or the check's own when its readings are noisier: a noisier day is not a
// change). Anything named: FAIL, recalibrate. Nothing named: the RMS over the calibration's
// level says pass, warn (noisier, or a change no few parameters explain) or fail. (A refit of all
// 54 parameters on a few dozen samples fits the noise and spreads one change over many correlated
// parameters: it named a moved joint 1-3 offset in 0 to 6 of 20 seeds.)
#pragma once

#include <robocal/kinematics/model.hpp>
#include <robocal/kinematics/sample.hpp>
#include <robocal/solver/assessment.hpp>
#include <robocal/solver/calibrate.hpp>

#include <optional>
#include <string>
#include <vector>

namespace robocal {

enum class HealthStatus { kPass, kWarn, kFail };
// "pass", "warn", "fail".
const char* healthStatusName(HealthStatus status);

// Where the level the check's RMS is compared with comes from.
enum class HealthReference {
  kBaseline,     // HealthOptions::baseline_rms_mm: a check run right after the calibration
  kCalibration,  // the active model's provenance rms_mm: the level its fit reached
  kFallback,     // HealthOptions::fallback_rms_mm: the model has no provenance
};
// "baseline", "calibration", "fallback".
const char* healthReferenceName(HealthReference reference);

struct HealthOptions {
  // The reference level, first of: the baseline when set (the RMS the same check gave right
  // after the calibration, which includes what the model cannot describe at the check's
  // extension), the active model's provenance rms_mm when it is positive, else the fallback (the
  // paper's final RMS, 0.084 mm).
  std::optional<double> baseline_rms_mm;
  double fallback_rms_mm = 0.084;
  // When nothing is named, the verdict on ratio = RMS of the check's residuals / the reference:
  // below warn_ratio pass, from warn_ratio warn, from fail_ratio fail. An unchanged robot gives
  // about 1.05 (the check is on another extension than the fit, and the RMS of 30 residuals
  // scatters by 1/sqrt(2n) = 13%), 1.6 (at most 2.3 in 200 seeds) when its readings are 1.5
  // times as noisy: neither is a change (docs/health-check.md has the counts).
  double warn_ratio = 2.5;
  double fail_ratio = 3.0;
  // Fewer samples than this: warn, whatever the ratio (the RMS of n samples scatters by about
  // 1/sqrt(2n) of itself: 16% at 20).
  int min_samples = 20;
  // The refit's prior: how far each kind of parameter is expected to move (1 sigma, interface
  // units; the simulate perturbation's sizes). The data are weighted with the reference level
  // as the measurement noise.
  double prior_translation_mm = 0.2;
  double prior_link_angle_deg = 0.02;
  double prior_joint_offset_deg = 0.05;
  double prior_gain = 0.0005;
  int max_iterations = 20;  // of each small refit
  // A parameter is named as moved when adding it to the refit lowers chi^2 = sum (r / noise)^2
  // by at least significance^2, the residuals whitened by the active model's own uncertainty
  // (its covariance: the calibration's error at the check's poses is not a change). With 3.5 an
  // unchanged robot is named something in 4 of 1,000 checks, 4 to 5 of 1,000 when the check is
  // 1.5 times as noisy and judged at its own level, where the significance is Student's t
  // equivalent for the check's degrees of freedom (docs/health-check.md). A model without a
  // covariance is not whitened: about 4% at 3.5, 2.5% at 4.
  double significance = 3.5;
  int max_named = 3;  // at most this many
  // Parameters whose Jacobian columns on the check's samples are this parallel (|cosine|) have
  // the same effect on these data: listed as ParameterChange::equivalent.
  double equivalent_cosine = 0.999;
  // So are those whose one-parameter step, at the named one's turn, explains the residual within
  // this much chi^2 of it (4: two sigmas): on a few dozen samples a 0.1 mm change of a link is
  // often told from its neighbours by less than that.
  double alternative_chi2 = 4.0;
};

// One parameter that moved, in interface units (mm, deg or a unitless gain).
struct ParameterChange {
  int index = 0;            // into ParamVector
  std::string name;         // paramName: "J2.offset", "L3.x"
  std::string unit;         // "mm", "deg" or "gain" (unitless)
  double change = 0;        // refit minus active
  double sigma = 0;         // posterior 1-sigma of the refit of the named parameters
  double prior_sigma = 0;   // the prior's 1-sigma
  double significance = 0;  // |change| / sigma
  double prior_ratio = 0;   // |change| / prior_sigma
  std::string text;         // "J2.offset +0.0500 deg"
  // Parameters with the same effect on the check's samples (their columns parallel, e.g. L1.z
  // for L0.z, L0.rz for J1.offset) or one that explains them within alternative_chi2 as well:
  // the data cannot tell this one from them.
  std::vector<std::string> equivalent;
};

struct HealthVerdict {
  HealthStatus status = HealthStatus::kPass;
  // One sentence: why this status ("RMS 0.092 mm is 1.09 times the calibration's 0.084 mm ...").
  std::string reason;
  std::size_t samples = 0;
  std::vector<Connection> connections;  // those in the check's samples, B1C1 ... B3C3 order
  std::vector<double> extensions_mm;    // the extensions in the check's samples, ascending

  // The check's residuals under the active model, no refit.
  ResidualStats residuals;  // count, rms_mm, mean_mm, max_abs_mm
  ShellTable shells;        // per shell, the worst named (a loose chuck shows in one)
  double reference_rms_mm = 0;
  HealthReference reference = HealthReference::kCalibration;  // where it came from
  double rms_ratio = 0;                                       // residuals.rms_mm / reference_rms_mm
  // The 1-sigma scatter of an unchanged robot's rms_ratio from the noise alone, 1/sqrt(2n) (the
  // mean square of n Gaussian residuals scatters by sqrt(2/n) of itself, its root by half that).
  double ratio_scatter = 0;
  double warn_ratio = 0, fail_ratio = 0;  // the thresholds applied

  // The noise level the changes were judged at: the reference, or the check's own level when
  // that is higher (check_level_mm: the RMS left after the named parameters, per degree of
  // freedom, sqrt(sum r^2 / (n - named))).
  double noise_mm = 0;
  double check_level_mm = 0;
  // Whether the active model carried its covariance, so that the test allowed for the model's
  // own error at the check's poses; without it that error is tested as if it were a change
  // (about 4% false alarms at the default significance).
  bool model_covariance = false;
  // What moved: the named parameters, most significant first (at most HealthOptions::max_named);
  // empty when nothing did. Anything here makes the verdict FAIL.
  std::vector<ParameterChange> moved;
  // The RMS left after the named parameters are refitted (the RMS above when none are): back
  // near the reference, they explain the change; still high, something else does (noise,
  // backlash, a loose chuck, more than max_named parameters).
  double refit_rms_mm = 0;
  double refit_ratio = 0;  // refit_rms_mm / reference_rms_mm
};

// The verdict on `check_samples` (a check run's, or any samples) under `active`, the calibrated
// model in use. Throws std::invalid_argument when there are no samples or one names a ball or
// chuck that does not exist, or an option is out of range.
HealthVerdict assessHealth(const Model& active, const std::vector<Sample>& check_samples,
                           const HealthOptions& options = {});

// "J2.offset +0.0500 deg" (4 decimals), "L3.x +0.210 mm" (3), "J4.gain +0.000500" (6).
std::string parameterChangeText(int index, double change);

// Whether the model carries a whole parameter covariance, which the verdict whitens by: 54 x 54,
// or 60 x 60 with the twists after them and the model's compliance (Model::covariance).
bool hasParamCovariance(const Model& model);

}  // namespace robocal
