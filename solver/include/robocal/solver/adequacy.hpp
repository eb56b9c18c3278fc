// The model-adequacy test of a fit: does the residual follow a pattern that betrays error the
// 54-parameter model does not contain? After a least-squares fit the residual is orthogonal to
// every direction the parameters can explain; what is left should be noise. Each pattern is a
// set of features, one column per sample, regressed on the residual:
//   - approach direction: joint j's angle off by +/- a constant with the sign of its last motion
//     (gear backlash): (dL/dtheta_j) * s_j, s_j the sign of the joint's move from the previous
//     sample (the samples in the order they were measured; the first of each shell unknown, 0);
//   - gravity torque: joints 2 and 3 twisting with the torque the arm's weight puts on them:
//     (dL/dtheta_j) * ((w - o_j) x down) . z_j, w the wrist centre, o_j and z_j joint j's axis;
//   - time: the links growing over the run (warm-up): t * dL/d(scale of the link translations),
//     t the sample's place in the run, 0 to 1 (by its time_s when every sample has one).
// A pattern is found when the residual's reduction by it, over sigma^2, exceeds the chi-square
// quantile of its features at `false_alarm` (1e-3): on an ideal robot it fires about once in a
// thousand fits. Its size is the RMS of the fitted pattern.
// With revisits (samples of the same shell at the same place: the plan's motion.revisit_every),
// the bar's noise is measured, not assumed: the spread of the residuals of each place about their
// mean (pure error). The fit's residual standard error is then tested against it (lack of fit):
// a residual too large for the noise, at the same false-alarm rate, is error the model does not
// contain even when it follows none of the patterns. No I/O.
#pragma once

#include <robocal/kinematics/model.hpp>
#include <robocal/kinematics/sample.hpp>
#include <robocal/solver/drift.hpp>

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace robocal {

// The upper quantile of the chi-square distribution with `dof` degrees of freedom (1 to 6) at
// `false_alarm` 1e-3 (or, above it, 1e-2).
double chi2Quantile(int dof, double false_alarm);

struct AdequacyPattern {
  std::string pattern;   // "approach direction", "gravity torque", "time"
  std::string detail;    // which joints, in words ("joints 2, 3")
  double chi2 = 0;       // reduction of sum (r / sigma)^2 by the pattern's features
  double threshold = 0;  // the chi-square quantile it was compared with
  int features = 0;
  double rms_mm = 0;  // RMS of the fitted pattern over the samples
  bool found = false;
};

struct Adequacy {
  bool ok = true;       // no pattern found
  double sigma_mm = 0;  // the residual's standard error the test used
  // RMS of the residual the found patterns explain together: error the model does not contain.
  double unmodelled_mm = 0;
  std::vector<AdequacyPattern> patterns;  // every pattern tested, found or not
  // From the revisits: how many places were measured more than once, the degrees of freedom of
  // their pure error, and the noise it measures (absent without revisits).
  int revisited_places = 0;
  int noise_dof = 0;
  std::optional<double> noise_mm;
  // sigma_mm over the measured noise, the largest ratio the noise explains at the false-alarm
  // rate (judged from 10 degrees of freedom), and whether the fit exceeds it.
  double fit_over_noise = 0, fit_over_noise_limit = 0;
  bool lack_of_fit = false;
  // The drift over the run from the places measured more than once (solver/drift.hpp): reported
  // and flagged, not a reason to refuse the fit by itself.
  Drift drift;
  // The error the model does not contain, RMS along the bar: the found patterns' part, or the
  // residual in excess of the measured noise, sqrt(sigma^2 - noise^2), when there is a lack of
  // fit and that is larger; 0 for an adequate fit. The calibrated model carries it
  // (ModelProvenance::unmodelled_mm) and its predicted position errors include it.
  double unmodelled_bar_mm() const;
  // One sentence for people: "0.042 mm of error the model does not contain; it follows the
  // approach direction of joints 2, 3", or "no pattern in the residual ...".
  std::string summary() const;
};

// `samples` in measurement order; `residuals` of the fit at `calibrated`; `sigma_mm` the fit's
// residual standard error.
Adequacy testAdequacy(const Model& calibrated, const std::vector<Sample>& samples,
                      const Eigen::VectorXd& residuals, double sigma_mm, double false_alarm = 1e-3);

}  // namespace robocal
