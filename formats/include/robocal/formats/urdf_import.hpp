// A serial chain of a URDF file as a robocal nominal model (docs/import.md): the other way from
// urdf.hpp. No file I/O: urdfToModel takes the file's text; `robocal import --urdf` reads it and
// writes the model.
//
// Contract:
// - The chain runs from `base_link` to `tip_link` (defaults below) through exactly six movable
//   joints, each revolute or continuous, and any number of fixed joints. A prismatic, floating or
//   planar joint on the way, a mimic joint, fewer or more than six, a base that is not above the
//   tip: std::invalid_argument naming the joint or link.
// - The model is T = L0 Rz(q1) L1 ... Rz(q6) L6 (model.hpp). A URDF joint turns about its `axis`,
//   any unit vector in its frame; robocal's joints turn about z. For each joint a rotation A_k
//   that takes z onto the axis is chosen (none when the axis is z, a half turn about x when it is
//   -z, otherwise the shortest rotation, then turned about its own z so that the link it ends has
//   ry = 0: away from the ZYX angles' gimbal lock, where a fit loses a parameter), and
//   R(axis, q) = A_k Rz(q) A_k^-1: L(k-1) holds the
//   fixed joints and the origin before joint k followed by A_k, and the next link starts with
//   A_k^-1. The forward kinematics are the URDF's to rounding at every joint value; the model's
//   link frames are the URDF's turned by A_k (the same when the axes are z).
// - Offsets 0, gains 1: the URDF joint value is the reading (radians in URDF, degrees in the
//   model). Limits: a revolute joint's lower and upper; a continuous joint -360 to 360 deg; its
//   velocity and effort, when the URDF gives them, as the joint's velocity_deg_per_s and
//   effort_nm.
// - Units: meters and radians in, mm and degrees out.
// - Balls and chucks: the links named ball1..ball3 fixed (through fixed joints only) below the
//   tip, and chuck1..chuck3 fixed below the base, as `robocal export --urdf` writes them; when a
//   URDF has none (any robot's own URDF), `fixtures_found` is false and they are zero: the caller
//   supplies them (the cell's fixtures are not the robot's).
// - Names: the joints' and the links' URDF names; the model's name is `options.name`, else
//   "<robot name> (URDF)".
#pragma once

#include <robocal/kinematics/model.hpp>

#include <string>
#include <vector>

namespace robocal {

struct UrdfImportOptions {
  // The chain's first and last link; "": chuck_fixture when the file has it (an export of
  // robocal's), else the root link; ball_fixture when the file has it, else the child link of
  // the sixth movable joint down from the base.
  std::string base_link, tip_link;
  std::string name;  // the model's name; "": "<robot name> (URDF)"
};

struct UrdfImport {
  Model model;
  std::string base_link, tip_link;        // the chain's ends as taken
  std::vector<std::string> fixed_joints;  // fixed joints merged into the link transforms
  bool fixtures_found = false;            // ball1..3 and chuck1..3 read from the file
};

// `source` names the file in errors ("ur5.urdf: ...").
UrdfImport urdfToModel(const std::string& urdf_text, const std::string& source,
                       const UrdfImportOptions& options = {});

}  // namespace robocal
