// Round axis ticks (1, 2, 5 steps) for the report's charts.
#include <robocal/formats/axis_ticks.hpp>

#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

using robocal::AxisTicks;
using robocal::niceTicks;

namespace {

std::vector<std::string> labels(const AxisTicks& t) {
  std::vector<std::string> out;
  for (double v : t.values()) out.push_back(t.label(v));
  return out;
}

// Every step is 1, 2 or 5 times a power of ten.
bool roundStep(double step) {
  const double mantissa = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
  return std::abs(mantissa - 1) < 1e-9 || std::abs(mantissa - 2) < 1e-9 ||
         std::abs(mantissa - 5) < 1e-9;
}

}  // namespace

TEST_CASE("axis ticks: the report's old figures get round steps", "[formats][ticks]") {
  // The examples: ticks at 0.0479 / 0.0959 mm and 82.8 / 55.2 samples.
  const AxisTicks residual = niceTicks(-0.2877, 0.2877);
  CHECK(residual.step == Approx(0.1));
  CHECK(labels(residual) ==
        std::vector<std::string>{"-0.3", "-0.2", "-0.1", "0.0", "0.1", "0.2", "0.3"});
  const AxisTicks counts = niceTicks(0, 331.2, 6, 0, 1);
  CHECK(counts.step == 50);
  CHECK(labels(counts).back() == "350");
  CHECK(labels(counts).front() == "0");
}

TEST_CASE("axis ticks: any range is covered by round steps with fitting labels",
          "[formats][ticks]") {
  for (double lo : {-1234.5, -3.3, -0.00071, 0.0, 0.02, 7.0})
    for (double span : {1e-4, 0.013, 0.9, 7.0, 55.0, 3600.0}) {
      const double hi = lo + span;
      const AxisTicks t = niceTicks(lo, hi);
      INFO("range " << lo << " .. " << hi << ": first " << t.first << " step " << t.step
                    << " count " << t.count);
      CHECK(roundStep(t.step));
      CHECK(t.first <= lo + 1e-12);
      CHECK(t.last() >= hi - 1e-12);
      CHECK(t.count >= 2);
      CHECK(t.count <= 13);  // about 6 intervals: never a crowd
      // Labels distinct, no "-0", and as many decimals as the step needs, no more.
      const auto l = labels(t);
      for (size_t k = 1; k < l.size(); ++k) CHECK(l[k] != l[k - 1]);
      for (const auto& s : l) {
        const bool minus_zero =
            s.rfind("-0", 0) == 0 && s.find_first_not_of("-0.") == std::string::npos;
        CHECK_FALSE(minus_zero);
      }
    }
}

TEST_CASE("axis ticks: a fixed step, a floor for counts, a single value", "[formats][ticks]") {
  const AxisTicks lon = niceTicks(0, 360, 6, 45);
  CHECK(lon.count == 9);
  CHECK(labels(lon)[1] == "45");
  CHECK(lon.last() == 360);
  const AxisTicks few = niceTicks(0, 2.3, 6, 0, 1);  // 2.3 samples: steps of 1, not 0.5
  CHECK(few.step == 1);
  CHECK(labels(few) == std::vector<std::string>{"0", "1", "2", "3"});
  const AxisTicks one = niceTicks(5, 5);
  CHECK(one.first < 5);
  CHECK(one.last() > 5);
  const AxisTicks quarter = niceTicks(0, 1, 4, 0.25);
  CHECK(labels(quarter) == std::vector<std::string>{"0.00", "0.25", "0.50", "0.75", "1.00"});
  CHECK(labels(niceTicks(0.1, 0.3, 2, 0.1)) == std::vector<std::string>{"0.1", "0.2", "0.3"});
}
