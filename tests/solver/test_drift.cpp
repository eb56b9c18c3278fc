// The drift of the places measured more than once (drift.hpp): a steady change of the reading
// over time is found with its rate, an unchanging robot is not flagged, and samples without times
// measure nothing.
#include <catch2/catch.hpp>

#include <robocal/solver/drift.hpp>

#include <random>

using namespace robocal;

namespace {

struct Readings {
  std::vector<Sample> samples;
  Eigen::VectorXd residuals;
};

// `places` places (one a shell), each measured `visits` times `every_min` apart, the residual
// growing by `rate_mm_per_h` with an offset of its own and Gaussian noise.
Readings drifting(double rate_mm_per_h, double noise_mm, unsigned seed, int places = 6,
                  int visits = 8, double every_min = 5) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0, noise_mm), offset(0, 0.05);
  Readings r;
  std::vector<double> residuals;
  double clock_s = 1.7e9;  // Unix time, as the daemon writes it
  for (int p = 0; p < places; ++p) {
    const double place_offset = offset(rng);
    for (int v = 0; v < visits; ++v) {
      Sample s;
      s.shell = p + 1;
      s.lat_deg = 10;
      s.time_s = clock_s + v * every_min * 60;
      r.samples.push_back(s);
      residuals.push_back(place_offset + rate_mm_per_h * (*s.time_s - clock_s) / 3600 + noise(rng));
      // A place measured once between them: no information on drift, left out.
      Sample once = s;
      once.lat_deg = 20 + v;
      r.samples.push_back(once);
      residuals.push_back(noise(rng));
    }
    clock_s += visits * every_min * 60 + 120;  // the next shell, after a swap
  }
  r.residuals =
      Eigen::Map<Eigen::VectorXd>(residuals.data(), static_cast<Eigen::Index>(residuals.size()));
  return r;
}

}  // namespace

TEST_CASE("drift: a steady change of the reference readings is found, with its rate and span") {
  const Readings r = drifting(0.05, 0.01, 1);
  const Drift d = measureDrift(r.samples, r.residuals);
  REQUIRE(d.measured);
  CHECK(d.places == 6);
  CHECK(d.readings == 48);
  CHECK(d.span_min == Approx(35));
  CHECK(d.rate_mm_per_h == Approx(0.05).margin(4 * d.rate_sigma_mm_per_h));
  CHECK(d.rate_sigma_mm_per_h < 0.015);
  CHECK(d.over_span_mm == Approx(std::abs(d.rate_mm_per_h) * 35 / 60));
  CHECK(d.found);
  CHECK_THAT(d.summary(), Catch::Matchers::Contains("drift found"));
}

TEST_CASE("drift: an unchanging robot is flagged in at most 1 of 200 runs, and the rate is noise") {
  int found = 0;
  double z2_sum = 0;
  for (unsigned seed = 1; seed <= 200; ++seed) {
    const Readings r = drifting(0, 0.03, 1000 + seed);
    const Drift d = measureDrift(r.samples, r.residuals);
    REQUIRE(d.measured);
    found += d.found;
    if (!d.significant) CHECK_THAT(d.summary(), Catch::Matchers::Contains("no drift told"));
    z2_sum += std::pow(d.rate_mm_per_h / d.rate_sigma_mm_per_h, 2);
  }
  CHECK(found <= 1);
  CHECK(z2_sum / 200 == Approx(1).margin(0.3));  // the standard error is the rate's scatter
}

TEST_CASE("drift: a change too small to matter is measured but not flagged") {
  // 0.005 mm/h over 35 min: 0.003 mm, clear of the noise but under the 0.01 mm limit.
  const Readings r = drifting(0.005, 0.0002, 3);
  const Drift d = measureDrift(r.samples, r.residuals);
  REQUIRE(d.measured);
  CHECK(d.rate_mm_per_h / d.rate_sigma_mm_per_h > 5);
  CHECK(d.over_span_mm < d.limit_mm);
  CHECK(d.significant);
  CHECK_FALSE(d.found);
  CHECK_THAT(d.summary(), Catch::Matchers::Contains("within the 0.010 mm allowed"));
}

TEST_CASE("drift: samples without times, or places measured once, measure nothing") {
  Readings r = drifting(0.05, 0.01, 4);
  for (Sample& s : r.samples) s.time_s.reset();
  Drift d = measureDrift(r.samples, r.residuals);
  CHECK_FALSE(d.measured);
  CHECK(d.places == 0);
  CHECK_THAT(d.summary(), Catch::Matchers::Contains("drift not measured"));

  r = drifting(0.05, 0.01, 5, 6, 1);  // every place once
  d = measureDrift(r.samples, r.residuals);
  CHECK_FALSE(d.measured);
  CHECK_FALSE(d.found);
}
