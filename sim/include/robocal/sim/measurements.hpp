// Simulated ball-bar measurements: a perturbed "true" robot, shell poses found with the nominal
// model, and the lengths the true robot would show. No I/O.
#pragma once

#include <robocal/kinematics/model.hpp>
#include <robocal/kinematics/sample.hpp>
#include <robocal/sim/true_robot.hpp>

#include <random>
#include <vector>

namespace robocal {

// Standard deviations of the Gaussian errors added to each of the 54 parameters. The defaults
// leave the balls about 1-2 mm from where the nominal model puts them.
struct PerturbationSigmas {
  double translation_mm = 0.2;     // link x, y, z
  double link_angle_deg = 0.02;    // link rz, ry, rx
  double joint_offset_deg = 0.05;  // joint offsets
  double gain = 0.0005;            // joint gains (unitless)
  // Every sigma times `factor` (a robot `factor` times as far from its model).
  PerturbationSigmas scaled(double factor) const {
    return {translation_mm * factor, link_angle_deg * factor, joint_offset_deg * factor,
            gain * factor};
  }
};

Model perturbModel(const Model& nominal, const PerturbationSigmas& sigmas, std::mt19937_64& rng);

// Length of the reference cell's ball-bar at zero deflection, without extension.
inline constexpr double kDefaultBarMm = 150.0;

struct ShellRequest {
  Connection connection;
  double radius_mm = kDefaultBarMm;  // bar nominal length + extension
  double extension_mm = 0;
  int points = 90;  // wanted data points on the shell's grid
  int shell = 1;    // number written to the samples
};

// One shell per connection and extension, extensions outermost, numbered from 1, each of radius
// kDefaultBarMm + extension with `points` wanted grid points.
std::vector<ShellRequest> shellRequests(const std::vector<Connection>& connections,
                                        const std::vector<double>& extensions_mm, int points);

struct ShellPose {
  double lat_deg = 0, lon_deg = 0;
  JointsDeg joints_deg = JointsDeg::Zero();
  // The vias the arm moves through on its way here (a plan's via steps); they decide, with the
  // point, the direction each joint last moved in (a true robot's backlash).
  std::vector<JointsDeg> vias_deg;
};

struct ShellPoses {
  std::vector<ShellPose> poses;
  int dropped = 0;  // grid points without a reachable pose inside the joint limits
};

// Latitude/longitude grid points on the upper hemisphere of the shell, each with a varied tool
// orientation (seeded by rng) solved by numerical IK of `model` (the nominal, as the planner
// would).
ShellPoses shellPoses(const Model& model, const ShellRequest& request, std::mt19937_64& rng);

struct MeasurementNoise {
  double length_sigma_mm = 0.084;  // LVDT and repeatability, Gaussian
  double joint_quantum_deg = 0;    // reading resolution; 0 = exact readings
};

// The samples a true robot that is exactly its model gives at the given joint positions:
// length = true distance + noise, readings quantised when asked.
std::vector<Sample> measureShell(const Model& truth, const ShellRequest& request,
                                 const std::vector<ShellPose>& poses, const MeasurementNoise& noise,
                                 std::mt19937_64& rng);

// Where a simulated run is: the arm's last readings, each joint's last direction of motion, and
// the time into the run (a true robot's backlash and warm-up depend on them).
struct RunTrack {
  bool started = false;
  JointsDeg last_deg = JointsDeg::Zero();
  Approach approach = kPositiveApproach;
  double minutes = 0;
  double minutes_per_point = 0.1;  // robot time a point costs, moves and dwell (the default plan's)
  void moveTo(const JointsDeg& q_deg);
};

// The samples a true robot with its realism gives along a run: each pose reached through its vias
// (the approach), at the run's time, the bar read through the instrument's errors, plus noise.
std::vector<Sample> measureShell(const TrueRobot& truth, const ShellRequest& request,
                                 const std::vector<ShellPose>& poses, const MeasurementNoise& noise,
                                 std::mt19937_64& rng, RunTrack& track);

}  // namespace robocal
