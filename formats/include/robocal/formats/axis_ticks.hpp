// Axis ticks people can read: steps of 1, 2 or 5 times a power of ten (0.01, 0.02, 0.05, 0.1,
// ...), the axis widened to whole steps, labels with just the decimals the step needs. Used by
// the report's SVG charts; the console's page (daemon/web) does the same in its script.
#pragma once

#include <string>
#include <vector>

namespace robocal {

struct AxisTicks {
  double first = 0;  // the first tick: the axis starts here
  double step = 1;
  int count = 1;     // ticks from first to last, both included
  int decimals = 0;  // what a label needs to show the step
  double last() const { return first + step * (count - 1); }
  double value(int k) const;
  std::vector<double> values() const;
  std::string label(double value) const;  // "0.05", "-20", never "-0"
};

// Ticks covering [lo, hi] with about `intervals` steps between them (at least one). A step of 0
// picks one; `fixed_step` > 0 imposes it (45 deg on a longitude axis); `min_step` > 0 sets a
// floor (1 for counts: no 0.5 samples).
AxisTicks niceTicks(double lo, double hi, int intervals = 6, double fixed_step = 0,
                    double min_step = 0);

}  // namespace robocal
