// The figures of an ISO 9283-style test with the ball-bar (docs/iso9283.md), from its samples and
// the model the robot is commanded with. A ball-bar measures one distance, from a fixed chuck to a
// ball on the tool, so the standard's figures come out along the bar:
//   - distance accuracy AD at each pose: the mean attained distance minus the commanded one (the
//     model's bar length at the pose's joints); ISO 9283's AD is between two poses, this is
//     between the chuck and the pose, the pose's position error along the bar;
//   - distance repeatability RD = 3 s of the attained distances over the cycles;
//   - AD and RD between pose pairs (P1 to each other pose): the change of the bar's length from
//     P1 to Pi within a cycle, against the commanded change;
//   - drift of P1 over the test: the change of its distance over the cycles' span (a regression
//     on time), ISO's dAP along the bar.
// Each figure with its 95 % interval: AD from Student's t, RD from the chi-square distribution of
// s^2, drift from the regression slope's t. The warm-up cycles (the plan's) are left out. Poses
// are the places the samples measure (placeOf), named P1, P2, ... in the order first measured.
// No I/O.
#pragma once

#include <robocal/kinematics/model.hpp>
#include <robocal/kinematics/sample.hpp>

#include <string>
#include <vector>

namespace robocal {

struct IsoFigure {
  double value_mm = 0;
  double low_mm = 0, high_mm = 0;  // the 95 % interval
};

struct IsoPose {
  std::string name;  // P1, P2, ...
  double lat_deg = 0, lon_deg = 0;
  int cycles = 0;           // measured cycles (after the warm-up)
  double commanded_mm = 0;  // the model's distance, chuck centre to ball centre
  double mean_attained_mm = 0;
  IsoFigure accuracy;       // AD
  IsoFigure repeatability;  // RD = 3 s
};

struct IsoPair {
  std::string from, to;
  int cycles = 0;
  double commanded_change_mm = 0;
  IsoFigure accuracy, repeatability;
};

struct IsoDrift {
  bool measured = false;  // P1 has times on at least 3 cycles
  double span_min = 0;
  IsoFigure change;  // of P1's distance over the span
};

struct IsoResult {
  std::string connection;  // "B1C1"
  double extension_mm = 0;
  int warmup_cycles = 0;
  int readings = 0;  // samples used (after the warm-up)
  std::vector<IsoPose> poses;
  std::vector<IsoPair> pairs;
  IsoDrift drift;
};

// 97.5 % quantile of Student's t with `dof` degrees of freedom (1 and up).
double studentT975(int dof);
// The p quantile (0 < p < 1) of the chi-square distribution with `dof` degrees of freedom.
double chiSquareQuantile(int dof, double p);

// Throws std::invalid_argument when the samples span more than one connection and extension, or
// no pose has two cycles after the warm-up.
IsoResult assessIsoTest(const Model& model, const std::vector<Sample>& samples, int warmup_cycles);

}  // namespace robocal
