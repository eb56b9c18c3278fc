// The verdict on one fit: the problems that make a calibrated model unfit to replace its nominal,
// one sentence each, saying what is wrong, why it matters and what to do. An empty list is a
// usable calibration. robocal solve exits non-zero on any, robocald does not activate such a
// model, and summary.html, RESULT and the console list them (they all read
// FitAssessment::problems, which assessFit fills from fitProblems).
//
// The rules, in the order they are reported (the likeliest cause first):
//   - units: joints that all lie within +/-2 pi (radians, not degrees), or bar lengths a
//     thousandth of the nominal model's (metres, not mm);
//   - rank below the robot's independent parameters;
//   - too few samples for the parameters: the fit has no redundancy to show its own error (a plan
//     of as many points as parameters fits any data exactly);
//   - a fit RMS far above a ball-bar's noise: the model does not describe the data;
//   - outliers found and kept in the fit;
//   - a predicted error above the nominal model's.
// Pure: no I/O.
#pragma once

#include <robocal/kinematics/model.hpp>
#include <robocal/kinematics/sample.hpp>

#include <optional>
#include <string>
#include <vector>

namespace robocal {

struct FitAssessment;

struct VerdictLimits {
  // A fit RMS above this is not noise: a ball-bar's is 0.05-0.1 mm (the paper's 0.084), the
  // realistic arm's unmodelled error adds a few hundredths (docs/accuracy.md).
  double max_fit_rms_mm = 0.5;
  // Samples per identified parameter at least: with fewer, the residuals cannot show the fit's
  // own error (n - rank degrees of freedom against rank parameters).
  double min_samples_per_parameter = 2.0;
  // The fit's residual standard error at most this many times the bar's noise that revisits
  // measured (when there are revisits and the excess is beyond chance, Adequacy::lack_of_fit):
  // at 1.5 the error the model does not contain is already larger than the noise.
  double max_fit_over_noise = 1.5;
};

// The units the samples seem to be written in, when they are not the files' (degrees, mm): a
// sentence naming the unit and the fix, or nothing. Needs at least 10 samples to judge.
std::optional<std::string> samplesUnitsProblem(const Model& nominal,
                                               const std::vector<Sample>& samples);

std::vector<std::string> fitProblems(const FitAssessment& a, const VerdictLimits& limits = {});

}  // namespace robocal
