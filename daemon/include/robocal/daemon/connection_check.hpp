// Whether the ball-bar is attached as the prompt asked. After the operator confirms a connection,
// the ball is moved a small step along the line from the expected chuck, out and in: a bar seated
// between that ball and that chuck changes its reading by the step. A free bar (not attached, or
// attached at one end only) does not change, and a bar in another chuck changes by the step's
// projection on its own line: both fail. Then the ball steps across that line, two ways: a bar on
// the right ball barely sees it (the model predicts the change, near zero), but a bar on a
// neighbouring ball, whose line from the same chuck is 20-35 degrees off, turns with it and
// changes by a third to a half of the step (such a wrong ball passed the along-line steps alone).
// Pure decision, no I/O (the run moves and reads).
#pragma once

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

namespace robocal::daemon {

struct ProbeStep {
  double commanded_mm;       // the ball's move along the expected bar line (+: away from the chuck)
  double reading_change_mm;  // the bar's averaged reading after the move minus before it
  double across_mm = 0;      // the ball's move across the expected bar line
  // The change the model predicts for the expected connection (commanded_mm when not given).
  std::optional<double> predicted_mm;
  double expected() const { return predicted_mm ? *predicted_mm : commanded_mm; }
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
    const double expected_mm = s.expected();
    const double tolerance_mm = kProbeTolerance * std::abs(expected_mm) + kProbeAllowanceMm;
    if (std::abs(s.reading_change_mm - expected_mm) <= tolerance_mm) continue;
    char buf[240];
    if (s.across_mm != 0) {
      std::snprintf(buf, sizeof buf,
                    "the bar reading changed by %+.3f mm when the ball moved %.3f mm across the "
                    "bar (expected %+.3f mm) (is the bar on the ball the prompt named? a bar on "
                    "another ball turns with this move)",
                    s.reading_change_mm, std::abs(s.across_mm), expected_mm);
      return buf;
    }
    std::snprintf(buf, sizeof buf,
                  "the bar reading changed by %+.3f mm when the ball moved %+.3f mm along the bar",
                  s.reading_change_mm, s.commanded_mm);
    const bool still = std::abs(s.reading_change_mm) < kProbeStill * std::abs(expected_mm);
    return std::string(buf) + (still ? " (a free bar: is it seated in both the ball and the chuck?)"
                                     : " (is it in the chuck and on the ball the prompt named?)");
  }
  return {};
}

}  // namespace robocal::daemon
