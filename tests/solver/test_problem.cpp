#include <catch2/catch.hpp>

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/robot/puma560.hpp>
#include <robocal/sim/measurements.hpp>
#include <robocal/solver/problem.hpp>

#include <random>

using namespace robocal;

TEST_CASE("the solver's bar-length model gives Kinematics' lengths and gradients") {
  std::mt19937_64 rng(5);
  // A model far from the nominal (several degrees, offsets of +-90 deg, gains off 1) and joint
  // readings over the whole range, so that no term can hide behind a zero.
  PerturbationSigmas sigmas;
  sigmas.translation_mm = 20;
  sigmas.link_angle_deg = 5;
  sigmas.joint_offset_deg = 60;
  sigmas.gain = 0.05;
  Model model = perturbModel(puma560NominalModel(), sigmas, rng);
  model.balls_mm[2] += Eigen::Vector3d(3, -7, 11);
  const ParamVector params = toParams(model);
  const Kinematics kin(params);
  const BarLengthModel bar(model, params);
  std::uniform_real_distribution<double> reading(-180, 180);
  for (int n = 0; n < 200; ++n) {
    Sample s;
    s.ball_index = n % kBallCount;
    s.chuck_index = (n / kBallCount) % kChuckCount;
    for (int j = 0; j < kJointCount; ++j) s.joints_deg[j] = reading(rng);
    const auto& ball = model.balls_mm[s.ball_index];
    const auto& chuck = model.chucks_mm[s.chuck_index];
    ParamRow expected, got;
    const double length = kin.barLengthGradient(s.joints_deg, ball, chuck, expected);
    CHECK(bar.length(s) == Approx(length).epsilon(1e-13));
    CHECK(bar.lengthGradient(s, got.data()) == Approx(length).epsilon(1e-13));
    const double scale = expected.cwiseAbs().maxCoeff();
    for (int i = 0; i < kParamCount; ++i) {
      INFO("parameter " << paramName(i) << " at sample " << n);
      CHECK(got[i] == Approx(expected[i]).margin(1e-12 * scale));
    }
  }
}
