// Numerical inverse kinematics (damped least squares) for any 54-parameter model. Used by the
// simulator; robot/ has the inverse kinematics of whole arms (arm.hpp: a closed form, or seeded).
#pragma once

#include <robocal/kinematics/kinematics.hpp>

#include <optional>

namespace robocal {

struct IkOptions {
  int max_iterations = 200;
  double position_tol_mm = 1e-7;
  double angle_tol_rad = 1e-10;
  double max_step_deg = 10.0;         // per iteration and joint
  double orientation_scale_mm = 200;  // weighs 1 rad of orientation error like this many mm
};

// Joint readings that put the last link's frame at `target`, starting from `seed`; nullopt when
// the iteration does not converge (unreachable or a bad seed). Joint limits are not checked.
std::optional<JointsDeg> solveIk(const Kinematics& kin, const Eigen::Isometry3d& target,
                                 const JointsDeg& seed, const IkOptions& options = {});

// True when every reading lies inside the model's limits shrunk by margin_deg on each side.
bool withinLimits(const Model& model, const JointsDeg& readings, double margin_deg = 0.0);

}  // namespace robocal
