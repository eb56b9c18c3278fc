// The ISO-style figures' statistics: the quantiles against published tables, and the figures of
// samples made to known values.
#include <robocal/kinematics/kinematics.hpp>
#include <robocal/robot/puma560.hpp>
#include <robocal/solver/iso9283.hpp>

#include <catch2/catch.hpp>

using namespace robocal;

TEST_CASE("the ISO figures' quantiles match the tables") {
  CHECK(studentT975(1) == Approx(12.706));
  CHECK(studentT975(29) == Approx(2.045));
  CHECK(studentT975(40) == Approx(2.021).epsilon(2e-3));
  CHECK(studentT975(120) == Approx(1.980).epsilon(2e-3));
  CHECK(chiSquareQuantile(29, 0.025) == Approx(16.047).epsilon(5e-3));
  CHECK(chiSquareQuantile(29, 0.975) == Approx(45.722).epsilon(5e-3));
  CHECK_THROWS(chiSquareQuantile(0, 0.5));
}

TEST_CASE("the ISO figures of samples made to known values") {
  const Model model = puma560NominalModel();
  const Kinematics kin(model);
  std::vector<Sample> samples;
  const JointsDeg q1 = (JointsDeg() << 10, -40, 170, 5, 60, 20).finished();
  const JointsDeg q2 = (JointsDeg() << 20, -40, 170, 5, 60, 20).finished();
  const double l1 = kin.barLength(q1, model.balls_mm[0], model.chucks_mm[0]);
  const double l2 = kin.barLength(q2, model.balls_mm[0], model.chucks_mm[0]);
  // Warm-up cycle 0 far off (left out); then P1 +0.1 +/- 0.01, P2 -0.2 exactly, P1 drifting.
  for (int k = 0; k < 11; ++k) {
    const double off = k == 0 ? 5.0 : 0.1 + (k % 2 ? 0.01 : -0.01);
    samples.push_back(makeSample(1, {0, 0}, 0, 10, 20, q1, l1 + off));
    samples.back().time_s = 60.0 * k;
    samples.push_back(makeSample(1, {0, 0}, 0, 10, 30, q2, l2 - 0.2));
    samples.back().time_s = 60.0 * k + 30;
  }
  const IsoResult r = assessIsoTest(model, samples, 1);
  REQUIRE(r.poses.size() == 2);
  CHECK(r.poses[0].cycles == 10);
  CHECK(r.poses[0].accuracy.value_mm == Approx(0.1));
  CHECK(r.poses[0].accuracy.low_mm < 0.1);
  CHECK(r.poses[0].repeatability.value_mm == Approx(3 * 0.01 * std::sqrt(10.0 / 9)).epsilon(1e-6));
  CHECK(r.poses[1].accuracy.value_mm == Approx(-0.2));
  CHECK(r.poses[1].repeatability.value_mm == Approx(0).margin(1e-9));
  REQUIRE(r.pairs.size() == 1);
  CHECK(r.pairs[0].accuracy.value_mm == Approx(-0.3));
  REQUIRE(r.drift.measured);
  CHECK(r.drift.span_min == Approx(9));
  CHECK(r.drift.change.low_mm < r.drift.change.value_mm);
  // Two connections are not one test.
  samples.push_back(makeSample(2, {1, 1}, 0, 10, 20, q1, 150));
  CHECK_THROWS_AS(assessIsoTest(model, samples, 1), std::invalid_argument);
}
