// Optimal plans (docs/plan-format.md, "Optimal plans"): the data points that make the calibrated
// model most accurate where the user works, for a budget of cell time or of points.
//
// The objective is the predicted RMS tool position error over the work volume after the fit:
// with J the plan's identification Jacobian on the 36 identified parameters (the other 18 fixed,
// as solveCalibration fixes them) and G_k the tool position's Jacobian at work pose k, the fit's
// covariance is C = sigma^2 (J^T J)^-1 and the objective is sqrt(trace(C W)), W = mean_k
// G_k^T G_k. Adding a point j changes it by a rank-one update, so a candidate is scored in
// O(36^2) without refactoring anything. Math only, no I/O.
//
// A plan chosen for the work volume alone is a knife-edge: it leaves directions of the parameter
// space that the work volume does not need almost unmeasured, and beyond the volume (the same box
// with the other shoulder, other orientations) the calibrated model can be worse than none. So
// the objective also weighs the arm's whole range: W = W_work + w W_whole, W_whole the same mean
// over joint vectors drawn within the limits, w the whole-range weight (docs/cell-time.md, "Robust
// plans": the predicted error is then sqrt(work^2 + w whole^2)).
#pragma once

#include <robocal/planner/plan.hpp>

#include <Eigen/Core>
#include <vector>

namespace robocal {

struct DesignOptions {
  double budget_s = 0;  // cell time: moves, dwells and the operator's swaps; 0: no limit
  int points = 0;       // data points; 0: as many as the budget allows
  GridSettings candidate_grid{5, 85, 5, 0, 15};  // the dense grid the points are chosen from
  int orientations = 3;                          // tool orientations tried per grid point
  int exchange_passes = 2;                       // point-exchange passes after the greedy pick
  double noise_sigma_mm = 0.084;                 // the bar's reading noise (the paper's)
  // The whole range's share of the objective (above) and its joint vectors; 0 or none: the work
  // volume alone.
  double whole_range_weight = 0;
  std::vector<JointsDeg> whole_range_joints;
  // Plan for a fit that also identifies the gravity compliance of the joints carrying the arm's
  // weight (robocal solve --compliance): their twist per N m joins the parameters the design
  // measures and the error it predicts. Needs the model's load (Model::compliance).
  bool compliance = false;
};

// The work-volume objective for one model: the identified parameters, their column scaling and
// W. The information matrices it takes are in scaled units, for rows from `row`.
class WorkVolumeCriterion {
 public:
  // `identified`: the parameters the fit estimates (Identifiability::identified).
  // `work_joints`: the nominal joints of the work volume's poses; `tool_point_mm` in the last
  // link's frame. Throws std::invalid_argument when work_joints is empty.
  // `whole_range_joints` with `whole_range_weight` > 0 add the whole range's term (above).
  // `compliance_joints` (0-based) add each one's twist per N m as a parameter: its effect is the
  // joint's offset column times its gravity torque at the pose (the model's load). Throws
  // std::invalid_argument when they are given and the model has no load.
  WorkVolumeCriterion(const Model& model, std::vector<int> identified,
                      const std::vector<JointsDeg>& work_joints,
                      const Eigen::Vector3d& tool_point_mm, double noise_sigma_mm,
                      const std::vector<JointsDeg>& whole_range_joints = {},
                      double whole_range_weight = 0, std::vector<int> compliance_joints = {});

  // Identified parameters, then the compliance's joints.
  int size() const { return static_cast<int>(identified_.size() + compliance_joints_.size()); }
  // The scaled, noise-weighted identification row of one bar measurement.
  Eigen::VectorXd row(const Connection& connection, const JointsDeg& joints) const;
  const Eigen::MatrixXd& weight() const { return w_; }
  // sqrt(trace(M^-1 W)) in mm: the predicted RMS tool position error for information M;
  // infinity when M is singular.
  double predictedRms(const Eigen::MatrixXd& information) const;

 private:
  // The unscaled columns of the criterion's parameters from all 54 (a Jacobian's columns, or a
  // gradient's entries) at `joints`.
  template <typename Full>
  Eigen::MatrixXd columns(const Full& full, const JointsDeg& joints) const;

  const Model& model_;
  std::vector<int> identified_;
  std::vector<int> compliance_joints_;
  Eigen::VectorXd scale_;  // per parameter: 1 / typical |d tool / d p| over the work volume
  Eigen::MatrixXd w_;
  double sigma_;
};

struct DesignReport {
  int candidates = 0;           // safe candidate points over all shells
  double predicted_rms_mm = 0;  // of the chosen plan, before the fit
  double predicted_cell_time_s = 0;
  int rounds = 0;  // selections made to meet the budget with the real motion
};

// The parameters a fit of these points would identify: as many as solveCalibration estimates,
// the best-conditioned ones (the same predicted tool error as the solver's own choice).
std::vector<int> identifiedParameters(const Model& model, const std::vector<Sample>& samples);

// Predicted RMS tool position error over the work volume (mm) of any plan's data points; with
// `compliance`, of a fit that also identifies the loaded joints' compliance (DesignOptions).
double predictedWorkVolumeError(const Model& model, const Plan& plan,
                                const std::vector<JointsDeg>& work_joints, double noise_sigma_mm,
                                bool compliance = false);

// The joints whose compliance a fit of these samples identifies (loadedJoints), for a design
// with `compliance`; none without. Throws std::invalid_argument when the model has no load.
std::vector<int> designComplianceJoints(const Model& model, const std::vector<Sample>& samples,
                                        bool compliance);

// Plans the cell with points chosen for the work volume: candidates on every shell of the
// cell's connections and extensions (candidate_grid x orientations, all passing the planner's
// safety rules), a greedy pick by objective gain per second of cell time (a shell's first point
// pays the operator's swap), exchange passes within shells, shells that do not pay for their
// swap dropped, each shell's points ordered for short motion, and the pick redone until the
// plan's real duration fits the budget. Shells that end with no points are left out. Throws
// PlanError when the options give no plan (no budget and no points; nothing reachable).
Plan planOptimal(const Model& model, const CellConfig& cell,
                 const std::vector<JointsDeg>& work_joints, const DesignOptions& options,
                 DesignReport* report = nullptr);

// One shell's safe candidates (ShellPlanner::candidatePoints) and which of them a design chose.
struct ShellChoice {
  Connection connection;
  double extension_mm = 0;
  const ShellCandidates* candidates = nullptr;
  std::vector<char> chosen;  // one flag per candidate point
};

// The plan of the chosen points of `planner`'s cell: each shell's in a short tour from its
// connect pose (shortTour), joined with vias by the planner (shells in parallel); shells with no
// point left out, the rest numbered from 1, the summary filled in (not rank or deflection).
Plan joinChosenPoints(const Model& model, const ShellPlanner& planner,
                      const std::vector<ShellChoice>& shells);

// Visiting order of points that starts at `start` and keeps the total move time short (nearest
// neighbour, then 2-opt): indices into `points`.
std::vector<size_t> shortTour(const ShellPlanner& planner, const JointsDeg& start,
                              const std::vector<ShellPoint>& points);

}  // namespace robocal
