// Whether the ball-bar is attached as the prompt asked. After the operator confirms a connection,
// the ball is moved a small step along the line from the expected chuck, out and in: a bar seated
// between that ball and that chuck changes its reading by the step. A free bar (not attached, or
// attached at one end only) does not change, and a bar in another chuck changes by the step's
// projection on its own line: both fail. Pure decision, no I/O (the run moves and reads).
#pragma once

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace robocal::daemon {

struct ProbeStep {
  double commanded_mm;       // the ball's move along the expected bar line (+: away from the chuck)
  double reading_change_mm;  // the bar's averaged reading after the move minus before it
};

// A step passes when the reading changed by the commanded amount within this share of it plus
// an allowance for the noise of two averaged readings and the arm's resolution (in cellsim's
// main job the error of a correct connection was 0.02 mm, 1 sigma). A bar in a chuck whose line
// is 45 degrees off changes by 0.7 of the step: 0.23 mm short on the 0.8 mm step, past its 0.15.
inline constexpr double kProbeTolerance = 0.12;
inline constexpr double kProbeAllowanceMm = 0.05;
// Below this share of the step the bar did not follow at all: a free bar.
inline constexpr double kProbeStill = 0.3;

// "" when every step passes; otherwise what was seen, for the pause reason.
inline std::string connectionCheckProblem(const std::vector<ProbeStep>& steps) {
  for (const ProbeStep& s : steps) {
    const double tolerance_mm = kProbeTolerance * std::abs(s.commanded_mm) + kProbeAllowanceMm;
    if (std::abs(s.reading_change_mm - s.commanded_mm) <= tolerance_mm) continue;
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "the bar reading changed by %+.3f mm when the ball moved %+.3f mm along the bar",
                  s.reading_change_mm, s.commanded_mm);
    const bool still = std::abs(s.reading_change_mm) < kProbeStill * std::abs(s.commanded_mm);
    return std::string(buf) + (still ? " (a free bar: is it seated in both the ball and the chuck?)"
                                     : " (is it in the chuck and on the ball the prompt named?)");
  }
  return {};
}

}  // namespace robocal::daemon
