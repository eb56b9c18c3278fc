// The adaptive dwell's decision (SteadyWindow) on synthetic readings made with the simulated
// cell's own settling model (sim/cellsim/settling.hpp), and the config keys that turn it on.
// No clocks: times are the readings' own.
#include <catch2/catch.hpp>

#include "../../sim/cellsim/settling.hpp"

#include <robocal/daemon/config.hpp>
#include <robocal/daemon/dwell_audit.hpp>
#include <robocal/daemon/steady_window.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <vector>

using namespace robocal::daemon;
using robocal::cellsim::SettlingModel;

namespace {

// Feeds readings at `rate_hz` from t = 1/rate until `until_s`; the time of the first steady
// window, if any.
template <typename Signal>
std::optional<double> firstSteady(SteadyWindow& w, double rate_hz, double until_s, Signal signal) {
  for (int k = 1; k / rate_hz <= until_s; ++k) {
    const double t = k / rate_hz;
    if (w.add(t, signal(t))) return t;
  }
  return std::nullopt;
}

SteadyCriteria criteria(double noise_mm) {
  SteadyCriteria c;
  c.noise_mm = noise_mm;
  c.window_s = 0.5;
  return c;
}

std::string configError(const nlohmann::json& extra) {
  nlohmann::json j = {{"model", "m.json"}, {"cell", "c.json"}};
  j.update(extra);
  try {
    daemonConfigFromJson(j, "robocald.json", "/tmp");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("settling model: amplitude grows with the move, capped, and decays", "[settling]") {
  const SettlingModel m;  // the defaults: 0.02 mm per 100 mm, at most 0.1 mm, 0.3 s, 8 Hz
  CHECK(m.amplitudeFor(100) == Approx(0.02));
  CHECK(m.amplitudeFor(200) == Approx(0.04));
  CHECK(m.amplitudeFor(5000) == Approx(0.1));
  CHECK(m.ring(0.1, 0) == Approx(0.1));
  CHECK(m.ring(0.1, -0.1) == 0);  // nothing before the move ends
  // A quarter period later the cosine crosses zero; half a period later it swings back.
  CHECK(std::abs(m.ring(0.1, 1 / 32.0)) < 1e-12);
  CHECK(m.ring(0.1, 1 / 16.0) < -0.08);
  // After the method's 2 s dwell the largest ring is far below a 1 um reader's noise.
  double after_dwell = 0;
  for (double t = 2.0; t < 2.2; t += 0.001)
    after_dwell = std::max(after_dwell, std::abs(m.ring(0.1, t)));
  CHECK(after_dwell < 0.0002);
  SettlingModel off = m;
  off.amplitude_mm_per_100mm = 0;
  CHECK(off.amplitudeFor(300) == 0);
  CHECK(off.ring(off.amplitudeFor(300), 0) == 0);
}

TEST_CASE("steady window: pure noise is steady soon after the window fills", "[settling]") {
  for (const double rate_hz : {20.0, 100.0}) {
    for (unsigned seed = 1; seed <= 20; ++seed) {
      std::mt19937_64 rng(seed);
      std::normal_distribution<double> noise(0, 0.001);
      SteadyWindow w(criteria(0.001));
      const auto t = firstSteady(w, rate_hz, 2.0, [&](double) { return 0.3 + noise(rng); });
      INFO("rate " << rate_hz << " Hz, seed " << seed);
      REQUIRE(t);
      CHECK(*t >= 0.45);  // never before the window is (nearly) full
      CHECK(*t < 1.5);    // 20 Hz: 10 readings a window, the spread judged loosely
    }
  }
}

TEST_CASE("steady window: a ringing tool is steady only once the ring is below the noise",
          "[settling]") {
  const SettlingModel m;
  const double noise_mm = 0.001;
  for (const double amplitude_mm : {0.02, 0.1}) {
    for (unsigned seed = 1; seed <= 10; ++seed) {
      std::mt19937_64 rng(seed);
      std::normal_distribution<double> noise(0, noise_mm);
      SteadyWindow w(criteria(noise_mm));
      const auto t =
          firstSteady(w, 100, 3.0, [&](double t) { return m.ring(amplitude_mm, t) + noise(rng); });
      INFO("amplitude " << amplitude_mm << " mm, seed " << seed);
      REQUIRE(t);
      // The envelope where the window judged steady began (t - window): at the noise level.
      const double envelope_at_window_start = amplitude_mm * std::exp(-(*t - 0.5) / 0.3);
      CHECK(envelope_at_window_start < 3 * noise_mm);
      // What is left when the dwell ends: a fraction of the noise.
      CHECK(amplitude_mm * std::exp(-*t / 0.3) < 0.6 * noise_mm);
      // A 20 um ring is judged steady before the method's 2 s; a 100 um one (100 x the noise)
      // about then.
      CHECK(*t < (amplitude_mm < 0.05 ? 2.0 : 2.5));
    }
  }
  // The larger ring takes longer.
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0, noise_mm);
  SteadyWindow small(criteria(noise_mm)), large(criteria(noise_mm));
  const auto t_small =
      firstSteady(small, 100, 3.0, [&](double t) { return m.ring(0.01, t) + noise(rng); });
  const auto t_large =
      firstSteady(large, 100, 3.0, [&](double t) { return m.ring(0.1, t) + noise(rng); });
  REQUIRE(t_small);
  REQUIRE(t_large);
  CHECK(*t_large > *t_small);
}

TEST_CASE("steady window: a slow drift, a late jump or too few readings are not steady",
          "[settling]") {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0, 0.001);
  {  // 5 um/s: 2.5 um across the window, 2.5 x the noise
    SteadyWindow w(criteria(0.001));
    CHECK_FALSE(firstSteady(w, 100, 3.0, [&](double t) { return 0.005 * t + noise(rng); }));
    CHECK(w.trendMm() > 0.0015);
  }
  {  // steady, then a 10 um jump: not steady again while the jump is inside the window
    SteadyWindow w(criteria(0.001));
    const auto t0 = firstSteady(w, 100, 2.0, [&](double) { return noise(rng); });
    REQUIRE(t0);
    const int k0 = static_cast<int>(std::lround(*t0 * 100));
    for (int k = k0 + 1; k < k0 + 48; ++k) CHECK_FALSE(w.add(k / 100.0, 0.01 + noise(rng)));
  }
  {  // 5 readings a second: never 8 in the window
    SteadyWindow w(criteria(0.001));
    CHECK_FALSE(firstSteady(w, 5, 3.0, [&](double) { return noise(rng); }));
  }
}

TEST_CASE("config: the adaptive dwell's keys are checked by name", "[settling]") {
  CHECK(configError(nlohmann::json::object()).empty());
  CHECK(configError({{"dwell_mode", "adaptive"}, {"bar_noise_mm", 0.002}}).empty());
  CHECK_THAT(configError({{"dwell_mode", "quick"}}),
             Catch::Contains("robocald.json: dwell_mode: fixed or adaptive"));
  // Without bar_noise_mm the connection check measures the noise; without the check, nothing does.
  CHECK(configError({{"dwell_mode", "adaptive"}}).empty());
  CHECK_THAT(configError({{"dwell_mode", "adaptive"}, {"connection_check_mm", 0}}),
             Catch::Contains("bar_noise_mm: required with dwell_mode adaptive when "
                             "connection_check_mm is 0"));
  CHECK_THAT(configError({{"adaptive_audit_every", -1}}),
             Catch::Contains("adaptive_audit_every: must be"));
  CHECK_THAT(configError({{"adaptive_audit_every", 2.5}}), Catch::Contains("adaptive_audit_every"));
  CHECK_THAT(configError({{"bar_noise_mm", -1}}), Catch::Contains("bar_noise_mm: must be"));
  CHECK_THAT(configError({{"dwell_mode", "adaptive"},
                          {"bar_noise_mm", 0.002},
                          {"settle_s", 0.4},
                          {"adaptive_window_s", 0.5}}),
             Catch::Contains("adaptive_window_s: must be below settle_s"));
  CHECK_THAT(configError({{"adaptive_window_s", "long"}}), Catch::Contains("adaptive_window_s:"));
  // A fixed dwell ignores the adaptive keys' relation to settle_s.
  CHECK(configError({{"settle_s", 0.02}}).empty());
}

TEST_CASE("still noise: the pooled standard deviation of windows read with the robot still",
          "[settling]") {
  StillNoise n;
  CHECK(n.mm() == 0);
  n.add(0.5, 1);  // one reading: no spread to pool
  CHECK(n.dof() == 0);
  n.add(0.002, 11);  // 10 degrees of freedom at 2 um
  n.add(0.004, 31);  // 30 at 4 um: pooled sqrt((10 x 4 + 30 x 16) / 40)
  CHECK(n.dof() == 40);
  CHECK(n.mm() == Approx(std::sqrt((10 * 4.0 + 30 * 16.0) / 40) * 1e-3));
  n.clear();
  CHECK(n.dof() == 0);
  CHECK(n.mm() == 0);
  // From real windows: the pooled figure recovers the noise the readings were drawn with.
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0, 0.003);
  for (int w = 0; w < 7; ++w) {
    std::vector<double> v(25);
    double mean = 0, squares = 0;
    for (double& x : v) mean += (x = 0.1 * w + noise(rng)) / 25;
    for (double x : v) squares += (x - mean) * (x - mean);
    n.add(std::sqrt(squares / 24), 25);
  }
  CHECK(n.mm() == Approx(0.003).epsilon(0.15));
}

TEST_CASE("dwell audit: a difference the noise explains passes, a bias fails, twice ends trust",
          "[settling]") {
  DwellAudit a;  // 4 sigma, one failure allowed
  // 10 readings each at 3 um: sigma of the difference 3 um x sqrt(0.2) = 1.34 um.
  DwellAudit::Verdict v = a.add(0.1040, 10, 0.1000, 10, 0.003);
  CHECK(v.sigma_mm == Approx(0.003 * std::sqrt(0.2)));
  CHECK(v.difference_mm == Approx(0.004));
  CHECK(v.passed);  // 3 sigma
  CHECK(a.trusted());
  v = a.add(0.1000, 10, 0.1080, 10, 0.003);  // -6 sigma
  CHECK_FALSE(v.passed);
  CHECK(a.trusted());  // one failure is allowed: four sigma happens in long runs
  CHECK(a.add(0.1, 10, 0.1, 10, 0.003).passed);
  CHECK(a.trusted());
  CHECK_FALSE(a.add(0.12, 10, 0.1, 10, 0.003).passed);
  CHECK_FALSE(a.trusted());
  CHECK(a.audits() == 4);
  CHECK(a.failures() == 2);
  // Unbiased windows of pure noise pass at about the normal rate (4 sigma: 6 in 100,000).
  DwellAudit b;
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0, 0.002);
  int failed = 0;
  for (int k = 0; k < 2000; ++k) {
    double ma = 0, mf = 0;
    for (int i = 0; i < 12; ++i) ma += noise(rng) / 12;
    for (int i = 0; i < 25; ++i) mf += noise(rng) / 25;
    failed += !b.add(ma, 12, mf, 25, 0.002).passed;
  }
  CHECK(failed <= 1);
}

TEST_CASE("config: the shipped robocald.json dwells adaptively, its noise measured and audited",
          "[settling]") {
  const DaemonConfig c = loadDaemonConfig(ROBOCAL_SOURCE_DIR "/config/robocald.json");
  CHECK(c.dwell_mode == "adaptive");
  CHECK(c.bar_noise_mm == 0);         // measured by each connection check...
  CHECK(c.connection_check_mm > 0);   // ... which is on
  CHECK(c.adaptive_audit_every > 0);  // and audited
  CHECK(c.adaptive_window_s < c.settle_s);
  CHECK(c.settle_s == 2.0);  // the method's bound
}
