// Accuracy where the user works (docs/compensation.md): tool poses over a work volume, each
// compensated, with the calibrated model's predicted error (its covariance; needs no truth) and,
// in simulation, the true robot's error when it is commanded with the nominal joints and with the
// compensated ones. Math only; accuracy_report.hpp writes the results.
#pragma once

#include <robocal/compensation/compensate.hpp>
#include <robocal/planner/cell.hpp>
#include <robocal/sim/true_robot.hpp>

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

namespace robocal {

// `work.poses` tool poses (world frame) drawn from the box and the angle ranges with `work.seed`,
// keeping those that compensate with status ok (compensator.forPose: the nominal model reaches
// them in some configuration, away from singularities, and so does the calibrated one). Throws
// std::invalid_argument when fewer than one in fifty draws is reachable (the volume is mostly out
// of the arm's reach: say so rather than loop).
std::vector<Eigen::Isometry3d> workVolumePoses(const WorkVolume& work,
                                               const Compensator& compensator);
// The same poses' compensated joints (with Compensator(nominal, nominal): the nominal joints, as
// an off-line program or the plan's work-volume objective has them).
std::vector<JointsDeg> workVolumeJoints(const WorkVolume& work, const Compensator& compensator);

struct ErrorStats {
  size_t count = 0;
  double rms = 0;
  double p95 = 0;  // nearest-rank 95th percentile
  double max = 0;
};
ErrorStats errorStats(std::vector<double> values);

struct PoseAccuracy {
  CompensatedTarget target;
  // Against the truth (simulation only): where the true robot's tool is when commanded with the
  // nominal readings and with the compensated ones, against the target; and the calibrated
  // model's own error there (true tool pose against the calibrated model's, at the compensated
  // readings).
  PoseDifference nominal_commanded, compensated_commanded, calibrated_model;
};

struct AccuracyReport {
  std::string poses_from;  // "work volume of cell.json" or the poses file
  size_t requested = 0;    // targets given
  size_t ok = 0;           // of which compensated with status ok
  // ok, or solved where the calibration says little (outside_measured, no_gain): the statistics
  // are over these, so a volume the calibration did not cover shows in them.
  size_t solved = 0;
  std::vector<PoseAccuracy> poses;  // every target, in order
  ErrorStats predicted_position_mm, predicted_orientation_deg;
  bool has_truth = false;
  ErrorStats nominal_position_mm, nominal_orientation_deg;
  ErrorStats compensated_position_mm, compensated_orientation_deg;
  ErrorStats calibrated_model_position_mm, calibrated_model_orientation_deg;
};

// Compensates every target pose and gathers the statistics over those solved. `truth`, when
// given, is the true robot of a simulation: with realism (sim/true_robot.hpp), the arm is judged
// as it works: warm (the warm-up over), carrying the truth's payload, and each target reached as
// the output commands it: up in every joint when the compensated target has its approach
// pre-point (the model records an approach), else from either side (a fixed pattern per target),
// as the nominal joints are. `configs`, when not empty, holds one entry a target:
// the arm configuration it must be reached in (nullopt: the best one), as a targets file's config
// column.
AccuracyReport assessAccuracy(const Compensator& compensator,
                              const std::vector<Eigen::Isometry3d>& targets,
                              const TrueRobot* truth = nullptr,
                              const std::vector<std::optional<ArmConfig>>& configs = {});
// The same for a program's nominal joints (Compensator::forNominalJoints): each target is the
// pose the nominal model puts there, in that configuration.
AccuracyReport assessAccuracyAtJoints(const Compensator& compensator,
                                      const std::vector<JointsDeg>& nominal_joints_deg,
                                      const TrueRobot* truth = nullptr);

}  // namespace robocal
