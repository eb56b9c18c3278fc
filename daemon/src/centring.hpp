// Keeping the bar centred while a shell runs: a model refined from the data so far (the
// centring fit), the refit rule, and the corrective move that brings the deflection back to zero.
// Math only: no I/O.
#pragma once

#include <robocal/kinematics/model.hpp>
#include <robocal/kinematics/sample.hpp>
#include <robocal/planner/cell.hpp>
#include <robocal/planner/plan.hpp>

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace robocal::daemon {

class Centring {
 public:
  // `samples`: what the run has measured before (a resume); refitted at once when enabled.
  Centring(const Model& nominal, const CellConfig& cell, bool enabled, std::vector<Sample> samples);
  bool enabled() const { return enabled_; }
  // The refined model once there is one, else the nominal.
  const Model& model() const { return refined_ ? *refined_ : nominal_; }
  bool refined() const { return refined_.has_value(); }
  // A measurement the fit may use: a data point, or one at a connect pose or after a correction
  // (they tell the model's error where the robot is about to go).
  void add(const Sample& sample) { samples_.push_back(sample); }
  void refit();
  // Refit as the data grow by 5% (every sample at first): a fit costs milliseconds that grow with
  // the samples, and a model from a few more samples changes little.
  bool refitDue() const {
    return enabled_ && samples_.size() >= refined_at_ + 1 + refined_at_ / 20;
  }

 private:
  const Model& nominal_;
  const CellConfig& cell_;
  bool enabled_;
  std::vector<Sample> samples_;
  std::optional<Model> refined_;
  std::size_t refined_at_ = 0;  // samples in the last refit
};

// The unit vector from the connection's chuck to its ball at joints `q`, and that distance (mm).
Eigen::Vector3d barDirection(const Model& model, const Connection& c, const JointsDeg& q);
double barLengthMm(const Model& model, const Connection& c, const JointsDeg& q);

// The joints that move the shell's ball by `move_mm` (the least joint motion that does), checked
// as correction() says; nullopt with the reason in `problem`.
std::optional<JointsDeg> ballMove(const Model& model, const CellConfig& cell,
                                  const ShellPlan& shell, const JointsDeg& q,
                                  const Eigen::Vector3d& move_mm, std::string& problem);

// The corrective move toward zero deflection: the ball moved along the bar by -deflection_mm.
// Checked like a planned pose before anything moves (limits, singularities, bar-tool angle,
// clearances; not the deviation from the shell, which is what it corrects), and a move of a few
// mm must stay a small turn of every joint: a larger one means a singular pose or a wrong model.
// Either gives the reason in `problem` and returns nullopt.
std::optional<JointsDeg> correction(const Model& model, const CellConfig& cell,
                                    const ShellPlan& shell, const JointsDeg& q,
                                    double deflection_mm, std::string& problem);

}  // namespace robocal::daemon
