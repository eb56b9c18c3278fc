#include <robocal/formats/axis_ticks.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace robocal {

namespace {

// 1, 2 or 5 times a power of ten, the smallest such step at least `raw`.
double roundStep(double raw) {
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double mantissa = raw / magnitude;
  const double nice = mantissa <= 1 ? 1 : mantissa <= 2 ? 2 : mantissa <= 5 ? 5 : 10;
  return nice * magnitude;
}

// Whole steps from below lo to above hi. A hair of tolerance: 0.3 / 0.1 is 2.9999999999999996.
long intervalsOf(double lo, double hi, double step) {
  return std::lround(std::ceil(hi / step - 1e-9) - std::floor(lo / step + 1e-9));
}

// The round step whose whole-step cover of [lo, hi] has the number of intervals nearest
// `wanted` (the larger step on a tie): 0..331 in 6 gets steps of 50 (7 intervals), not 100 (4).
double bestStep(double lo, double hi, int wanted) {
  const double raw = (hi - lo) / wanted;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double best = 0;
  long best_miss = 0;
  for (double m : {0.5, 1.0, 2.0, 5.0, 10.0, 20.0}) {
    const double step = m * magnitude;
    const long miss = std::labs(intervalsOf(lo, hi, step) - wanted);
    if (best == 0 || miss <= best_miss) best = step, best_miss = miss;
  }
  return best;
}

}  // namespace

double AxisTicks::value(int k) const {
  // Computed from the index, not by summing steps: 0.1 + 0.1 + 0.1 must print as 0.3.
  const double v = first + step * k;
  const double scale = std::pow(10.0, decimals);
  return std::round(v * scale) / scale;
}

std::vector<double> AxisTicks::values() const {
  std::vector<double> out;
  for (int k = 0; k < count; ++k) out.push_back(value(k));
  return out;
}

std::string AxisTicks::label(double v) const {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  std::string s = buf;
  if (s.find_first_not_of("-0.") == std::string::npos && s[0] == '-') s.erase(0, 1);  // "-0.00"
  return s;
}

AxisTicks niceTicks(double lo, double hi, int intervals, double fixed_step, double min_step) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) lo = 0, hi = 1;
  if (lo > hi) std::swap(lo, hi);
  if (hi - lo <= 0) {  // one value: a range around it
    const double pad = lo != 0 ? std::abs(lo) * 0.1 : 1.0;
    lo -= pad;
    hi += pad;
  }
  double step = fixed_step > 0 ? fixed_step : bestStep(lo, hi, std::max(1, intervals));
  if (min_step > 0 && step < min_step) step = roundStep(min_step);
  AxisTicks t;
  t.step = step;
  t.first = std::floor(lo / step + 1e-9) * step;
  t.count = static_cast<int>(intervalsOf(lo, hi, step)) + 1;
  t.decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  // 2.5 is not a step this makes, but a fixed step may have a fraction the rule above misses.
  if (fixed_step > 0) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.10g", fixed_step);
    const std::string s = buf;
    const auto dot = s.find('.');
    if (dot != std::string::npos) t.decimals = std::max<int>(t.decimals, s.size() - dot - 1);
  }
  return t;
}

}  // namespace robocal
