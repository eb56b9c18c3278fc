// The drift of the robot and the bar over a run, measured: the places a plan measures more than
// once (a shell's reference pose, motion.reference_every_min, and the revisits of
// motion.revisit_every) read the same distance each time unless something changed in between
// (warm-up of the links, the bar's electronics). Within each place, the fit's residual is
// regressed on the time of measurement (Sample::time_s): one slope for the whole run, pooled over
// the places, with its standard error from their scatter about it. The drift is found when the
// slope differs from zero at `false_alarm` (1e-3) and the change it makes over the longest span a
// place was measured exceeds `limit_mm`. No I/O.
#pragma once

#include <robocal/kinematics/sample.hpp>

#include <Eigen/Core>
#include <string>
#include <tuple>
#include <vector>

namespace robocal {

// Where a sample was measured: its shell, connection, extension and place on the shell. Samples
// of one place measure the same distance (the plan's revisits and reference pose); the adequacy
// test's pure error and the drift both group by it.
using SamplePlace = std::tuple<int, int, int, double, double, double>;
inline SamplePlace placeOf(const Sample& s) {
  return {s.shell, s.ball_index, s.chuck_index, s.extension_mm, s.lat_deg, s.lon_deg};
}

// A change over a place's span below this is not worth a flag: a tenth of what the compensated
// arm misses by (docs/accuracy.md), and below the LVDT's own nonlinearity.
inline constexpr double kDriftLimitMm = 0.01;

struct Drift {
  int places = 0;         // places measured at least twice, with times
  int readings = 0;       // their measurements
  double span_min = 0;    // the longest time between a place's first and last measurement
  bool measured = false;  // enough of them for a slope with its standard error
  double rate_mm_per_h = 0, rate_sigma_mm_per_h = 0;  // the residual's change per hour, 1 sigma
  double over_span_mm = 0;  // |rate| * span: the change a place sees over its span
  double limit_mm = kDriftLimitMm;
  bool significant = false;  // the rate differs from zero at the false-alarm rate
  bool found = false;        // significant, and over_span_mm past limit_mm
  // One sentence for people: "the reading drifts 0.021 mm/h (+/- 0.004, 1 sigma): 0.015 mm over
  // the 43 min a reference pose was measured, more than the 0.010 mm allowed".
  std::string summary() const;
};

// `samples` with their `residuals` (any order); samples without a time are left out.
Drift measureDrift(const std::vector<Sample>& samples, const Eigen::VectorXd& residuals,
                   double false_alarm = 1e-3, double limit_mm = kDriftLimitMm);

}  // namespace robocal
