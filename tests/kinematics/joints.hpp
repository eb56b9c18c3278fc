// Test helper: six joint readings (deg) written out in one call.
#pragma once

#include <robocal/kinematics/model.hpp>

namespace robocal::test {

inline JointsDeg deg(double a, double b, double c, double d, double e, double f) {
  JointsDeg q;
  q << a, b, c, d, e, f;
  return q;
}

}  // namespace robocal::test
