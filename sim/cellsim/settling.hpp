// The simulated cell's settling: after a move ends, the tool rings along the bar with a decaying
// oscillation, and the bar reads it on top of the true length:
//
//   ring(t) = A * exp(-t / tau) * cos(2 pi f t),   t = seconds since the move ended (cell time)
//   A       = min(amplitude_mm_per_100mm * tool travel / 100 mm, max_amplitude_mm)
//
// Pure and header-only so that tests can check it without ptys. Defaults are an assumption (no
// measured settling of our PUMA 560 is published; see docs/settling.md): a wrist with a bar
// rings at a few to ~15 Hz and decays in tenths of a second, so that after the method's 2 s
// dwell (method.md, "Data collection") the ringing is far below the LVDT's noise.
#pragma once

#include <algorithm>
#include <cmath>

namespace robocal::cellsim {

struct SettlingModel {
  double amplitude_mm_per_100mm = 0.02;  // ringing amplitude per 100 mm of tool travel (0: off)
  double max_amplitude_mm = 0.1;         // cap, whatever the move
  double time_constant_s = 0.3;          // exp(-t / tau) envelope
  double frequency_hz = 8.0;             // along the bar

  bool enabled() const { return amplitude_mm_per_100mm > 0 && max_amplitude_mm > 0; }
  // The starting amplitude after a move that carried the tool `travel_mm`.
  double amplitudeFor(double travel_mm) const {
    return enabled() ? std::min(max_amplitude_mm, amplitude_mm_per_100mm * travel_mm / 100.0) : 0;
  }
  // The ring `t_s` seconds after the move ended, from a starting amplitude (0 before the end).
  double ring(double amplitude_mm, double t_s) const {
    if (amplitude_mm == 0 || t_s < 0 || time_constant_s <= 0) return 0;
    constexpr double kTwoPi = 6.283185307179586;
    return amplitude_mm * std::exp(-t_s / time_constant_s) * std::cos(kTwoPi * frequency_hz * t_s);
  }
};

}  // namespace robocal::cellsim
