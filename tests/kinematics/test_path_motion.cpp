// The blended path model robocal-cellsim runs and the planner checks (path_motion.hpp).
#include <catch2/catch.hpp>

#include "joints.hpp"

#include <robocal/kinematics/path_motion.hpp>

using namespace robocal;
using test::deg;

namespace {

double maxDiff(const JointsDeg& a, const JointsDeg& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

}  // namespace

TEST_CASE("a path: through every via unblended, corners cut inside when blended",
          "[kinematics][paths]") {
  const JointsDeg start = deg(0, 45, -90, 0, 45, 0);
  // Three steps of 10 deg of joint 1 each; joint 2 at 2, then 3, then 2 deg a step.
  const std::vector<JointsDeg> steps{deg(10, 47, -88, 0, 45, 0), deg(20, 50, -86, 2, 45, 0),
                                     deg(30, 52, -85, 4, 44, 0)};
  const PathMotion linear(start, steps, 10, 0);
  CHECK(linear.durationS() == Approx(3.0));  // 10 deg of joint 1 a segment at 10 deg/s
  CHECK(linear.reachedS(2) == Approx(2.0));
  CHECK(maxDiff(linear.at(1.0), steps[0]) < 1e-9);
  CHECK(maxDiff(linear.at(2.0), steps[1]) < 1e-9);
  CHECK(maxDiff(linear.at(3.0), steps[2]) < 1e-9);
  CHECK(maxDiff(linear.at(-1), start) == 0);
  CHECK(maxDiff(linear.target(), steps[2]) == 0);
  CHECK(maxDiff(linear.lastFrom(), steps[1]) == 0);

  // A blend of 4 deg of travel: 0.4 s at 10 deg/s, and the same path at any speed.
  const PathMotion blended(start, steps, 10, 4);
  CHECK(blended.durationS() == Approx(3.4));  // at rest one blend after the last segment
  CHECK(maxDiff(blended.at(3.4), steps[2]) < 1e-9);
  CHECK(maxDiff(blended.at(0), start) < 1e-9);
  const PathMotion slower(start, steps, 2, 4);
  CHECK(maxDiff(slower.at(5 * 1.2), blended.at(1.2)) < 1e-9);
  // Half a blend past the first via the arm is off it by the corner's cut, about
  // |velocity change| x blend / 8: joint 2's goes from 2 to 3 deg/s (0.05 deg); never more than
  // the largest change's 4 deg/s x 0.4 s / 8 = 0.2 deg anywhere.
  const double at_via = maxDiff(blended.at(1.0 + 0.2), steps[0]);
  CHECK(at_via > 0.01);
  CHECK(at_via < 0.2);
  for (double t = 0; t <= 3.4; t += 0.01) {
    const JointsDeg q = blended.at(t);
    CHECK(q[0] >= start[0] - 1e-9);  // joint 1 never runs backwards: no stop, no overshoot
    CHECK(q[0] <= steps[2][0] + 1e-9);
  }
}
