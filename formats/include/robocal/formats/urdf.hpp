// A robocal model as a URDF file (docs/export.md), for tools that speak URDF (ROS, visualizers,
// planners). No I/O: modelToUrdf returns the file's text; `robocal export --urdf` writes it.
//
// Contract of the text modelToUrdf returns:
// - Links: chuck_fixture (the root: the model's global frame, the chuck fixture's), link1 ..
//   link6 (the frame of joint k, turning with it), ball_fixture (the frame after L6, in which the
//   model gives its balls), and fixed child links ball1 .. ball3 (of ball_fixture, at the balls'
//   centres) and chuck1 .. chuck3 (of chuck_fixture, at the chucks' centres). Links have no
//   geometry, inertia or collision: the model knows none.
// - Joints: six revolute joints, axis 0 0 1, chained chuck_fixture -> link1 -> ... -> link6;
//   joint k's origin is L(k-1) * Rz(offset k) relative to the previous link's frame, and a fixed
//   joint link6 -> ball_fixture holds L6. Joint k's URDF value is gain_k * reading_k (the
//   controller's reading in radians): then the URDF's forward kinematics are the model's,
//   T = L0 * J1 * L1 * ... * J6 * L6, to rounding. When every gain is 1 the joint value is the
//   reading.
// - Joint names: the model's joint names when they are six different, non-empty names that are
//   not the fixed joints' (ball_fixture_joint, ball1_joint, ...); otherwise J1 .. J6.
// - Limits: lower and upper are the model's reading limits (min, max) in radians; velocity
//   (rad/s) and effort (N m) the joint's velocity_deg_per_s and effort_nm, else the options'
//   (urdfLimits). Never 0: a joint with neither is refused (URDF requires them, and a velocity
//   of 0 is a joint MoveIt cannot move).
// - Units: meters and radians; origins are xyz and fixed-axis rpy (R = Rz(yaw) Ry(pitch)
//   Rx(roll)), every number printed with the fewest digits that read back as the same double.
// - An XML comment before <robot> states the model's name, its source and provenance, the frames,
//   the units, every joint gain (URDF cannot hold one) and what a gain other than 1 means.
//   Free text (names, paths) is made safe for a comment and for an attribute.
//
// Throws std::invalid_argument when a parameter, ball or chuck is not finite, or a gain is zero.
#pragma once

#include <robocal/kinematics/model.hpp>

#include <array>
#include <string>

namespace robocal {

struct UrdfOptions {
  std::string robot_name;  // <robot name="...">; empty: urdfRobotName(model)
  std::string source;      // where the model was read from, stated in the comment; "" not stated
  // For joints whose model has none (0): the rated speed and torque to write; 0: none given.
  double velocity_deg_per_s = 0;
  double effort_nm = 0;
};

// Each joint's velocity (deg/s) and effort (N m) as modelToUrdf writes them: the model's, else
// the options'. `missing` gets the joints left with a 0, in words ("J1 velocity, J1 effort"; ""
// when none).
struct UrdfJointLimits {
  double velocity_deg_per_s = 0, effort_nm = 0;
};
std::array<UrdfJointLimits, kJointCount> urdfLimits(const Model& model, const UrdfOptions& options,
                                                    std::string* missing = nullptr);

std::string modelToUrdf(const Model& model, const UrdfOptions& options = {});

// The robot name made from the model's name: lower case letters, digits and single '_' ("PUMA 560
// nominal (Lloyd DH)" -> "puma_560_nominal_lloyd_dh"); "robot" when that leaves nothing.
std::string urdfRobotName(const Model& model);

// The URDF links' and joints' names, for the command's summary and the tests.
inline constexpr const char* kUrdfBaseLink = "chuck_fixture";
inline constexpr const char* kUrdfBallFixtureLink = "ball_fixture";
// The six revolute joints' names as modelToUrdf writes them (see the contract above).
std::array<std::string, kJointCount> urdfJointNames(const Model& model);

}  // namespace robocal
