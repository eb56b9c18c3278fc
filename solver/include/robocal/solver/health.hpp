// The health check's verdict (docs/health-check.md): does the calibrated model in use still fit the
// robot? A short verification run (planner/health_plan.hpp: three connections, an extension the
// calibration did not use, about 72 points) is predicted by the active model without refitting;
// its RMS residual over the level the calibration itself reached says pass, warn or fail. A small
// refit from the active model, pulled toward it by a prior, then names what moved: parameters
// are added one at a time, each the one whose change (prior-weighted) explains most of what is
// left, while that is significant; the named ones are refitted together. (A refit of all 54
// parameters on ~70 samples fits the noise and spreads one change over many correlated
// parameters: it named a moved joint 1-3 offset in 0 to 6 of 20 seeds.)
// Plain data, no I/O (formats/health_report.hpp turns a verdict into text and JSON).
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
  // Verdict on ratio = RMS of the check's residuals / the reference: below warn_ratio pass, from
  // warn_ratio warn, from fail_ratio fail. In simulation an unchanged robot gives 1.05 +/- 0.09,
  // at most 1.29 in 200 seeds (the fit RMS is about 0.98 sigma, the check is on another
  // extension, and the RMS of ~70 residuals scatters by 1/sqrt(2n) = 8.5%); 0.05 deg on joint 1,
  // 2 or 3 gives 2.8 to 5.6, 0.2 mm on a link 1.2 to 2.5 (docs/health-check.md has the counts).
  double warn_ratio = 1.3;
  double fail_ratio = 1.5;
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
  // by at least significance^2: with 4, noise alone names one of the 54 in about 0.3% of checks.
  double significance = 4.0;
  int max_named = 3;  // at most this many
  // Parameters whose Jacobian columns on the check's samples are this parallel (|cosine|) have
  // the same effect on these data: listed as ParameterChange::equivalent.
  double equivalent_cosine = 0.999;
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
  // Parameters with the same effect on the check's samples (their columns parallel): the data
  // cannot tell this one from them, e.g. L1.z for L0.z, L0.rz for J1.offset.
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

  // What moved: the named parameters, most significant first (at most HealthOptions::max_named);
  // empty when nothing did.
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

}  // namespace robocal
