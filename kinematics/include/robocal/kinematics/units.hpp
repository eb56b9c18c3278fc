// Degrees and radians: the files and the operator speak degrees, the math radians. Defined once
// here for every module (kinematics is at the bottom of the dependency order).
#pragma once

#include <numbers>

namespace robocal {

inline constexpr double kRadPerDeg = std::numbers::pi / 180.0;
inline constexpr double kDegPerRad = 180.0 / std::numbers::pi;

constexpr double degToRad(double deg) {
  return deg * kRadPerDeg;
}
constexpr double radToDeg(double rad) {
  return rad * kDegPerRad;
}

}  // namespace robocal
