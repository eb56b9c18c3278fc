// Standard Denavit-Hartenberg parameters of a model (the inverse of modelFromStandardDH,
// model.hpp), for analytic-IK code and tools that take a DH table (docs/export.md, "DH table"). No
// I/O.
//
//   T = base * A1 * A2 * ... * A6 * tool,  A_i = Rz(theta_i) * Tz(d_i) * Tx(a_i) * Rx(alpha_i),
//   theta_i = theta_offset_i + gain_i * reading_i
//
// base and tool are general rigid transforms (the model's L0 and L6 need all six numbers); the
// tool frame is the model's tool frame (after L6, where its balls are given). Frame i-1's z axis
// is joint i's axis. A DH row has four numbers where a Sheth-Uicker link has six: the two left
// over (a shift along the next axis and a turn about it) fold into d and theta_offset, so DH is
// exact for any chain of axes, except where two consecutive axes are (nearly) parallel: their
// common normal is then undefined or far away (Hayati's objection). Axes within
// `parallel_tolerance_deg` of parallel are taken as parallel: the normal is drawn from the previous
// frame's origin, and the turn between them that DH cannot hold is lost: that is the table's
// error, measured against the model and stated with it. Gravity compliance is left out (a rigid
// arm); gains stay per joint (a DH table has none: the joint value is gain * reading).
#pragma once

#include <robocal/kinematics/model.hpp>

#include <Eigen/Geometry>
#include <array>
#include <vector>

namespace robocal {

struct DhTable {
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d tool = Eigen::Isometry3d::Identity();
  std::array<DHRow, kJointCount> rows{};  // model.hpp's, as modelFromStandardDH takes them
  std::array<double, kJointCount> gains{};
  // Joints i (1-based) whose axis was taken as parallel to joint i+1's.
  std::vector<int> parallel_joints;
  // The table against the model's rigid forward kinematics, over `checks` joint vectors drawn
  // within the joint limits: the worst tool-frame position and orientation error.
  int checks = 0;
  double max_position_error_mm = 0, max_rotation_error_deg = 0;
};

inline constexpr double kDhParallelToleranceDeg = 0.5;

// The table of `model` (its rigid chain at zero readings), checked at `checks` random joint
// vectors (seeded by `seed`).
DhTable dhFromModel(const Model& model, double parallel_tolerance_deg = kDhParallelToleranceDeg,
                    int checks = 1000, unsigned seed = 1);

// The tool frame's pose by the table at `readings` (deg).
Eigen::Isometry3d dhToolPose(const DhTable& table, const JointsDeg& readings);

}  // namespace robocal
