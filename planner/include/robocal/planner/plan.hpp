// The off-line plan: for each connection and extension a shell of data points on the sphere of
// radius L around the chuck, joined by via points so that the joint-interpolated motion keeps the
// bar within its tolerance for the nominal model. No I/O (plan_json.hpp reads and writes plans).
#pragma once

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/sample.hpp>
#include <robocal/planner/cell.hpp>
#include <robocal/robot/arm.hpp>

#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace robocal {

// Settings that cannot give a plan (radius out of reach, empty grid, impossible margins).
class PlanError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class StepKind { kVia, kPoint };

struct PlanStep {
  StepKind kind = StepKind::kPoint;
  JointsDeg joints_deg = JointsDeg::Zero();
  double lat_deg = 0, lon_deg = 0;  // where the ball is on the shell (vias too)
  // A point's measurement of the same place: 0 the first, then 1, 2, ... for its revisits
  // (motion.revisit_every) and, for a shell's reference pose, its repeats
  // (motion.reference_every_min).
  int visit = 0;
  // A via the arm stops at even when it moves through vias (motion.through_vias): the blended
  // corner here would leave the bar's tolerance (ShellPlanner::blendedPathProblem).
  bool stop = false;
};

// The arm comes to rest at this step: every point, and a via unless motion.through_vias.
inline bool stopsAt(const MotionSettings& motion, const PlanStep& step) {
  return step.kind == StepKind::kPoint || !motion.through_vias || step.stop;
}

// The stretch the arm runs from steps[first] on without coming to rest: its last step (the first
// one from there it stops at, or the shell's last) and the joints of first..last.
struct Stretch {
  std::size_t last = 0;
  std::vector<JointsDeg> joints_deg;
};
inline Stretch stretchFrom(const MotionSettings& motion, const std::vector<PlanStep>& steps,
                           std::size_t first) {
  Stretch s{first, {}};
  while (s.last + 1 < steps.size() && !stopsAt(motion, steps[s.last])) ++s.last;
  for (std::size_t k = first; k <= s.last; ++k) s.joints_deg.push_back(steps[k].joints_deg);
  return s;
}

// Where a point at `q` is approached from: every joint `step_deg` below it, and one joint
// further so that the bar between `ball` (tool frame) and `chuck` keeps its length at q (that
// joint at most 1 deg below q, so where it cannot, the pose check drops the point): each joint
// then moves into q upward and a
// real arm's backlash sits on the same side (motion.approach_deg; the daemon's connection check).
JointsDeg approachPrePoint(const Kinematics& kin, const Eigen::Vector3d& ball,
                           const Eigen::Vector3d& chuck, const JointsDeg& q, double step_deg);

// The pre-points that bring the joints up into `q` from `step_deg` below when the bar's length
// may change by at most `max_change_mm` at a pre-point (the daemon's connection check): the one
// of approachPrePoint when it keeps to that; else the joints step back and up again a group at a
// time (joints 1, 2, ... gathered while the group's pre-point keeps to it), so that a big arm,
// whose 0.02 deg moves the ball more than the check's own step, still has every joint's backlash
// on the same side. The caller moves to each pre-point and back to `q` in turn. A joint whose own
// step changes the bar by more than max_change_mm is left out: `left_out` lists them (0-based).
std::vector<JointsDeg> approachStages(const Kinematics& kin, const Eigen::Vector3d& ball,
                                      const Eigen::Vector3d& chuck, const JointsDeg& q,
                                      double step_deg, double max_change_mm,
                                      std::vector<int>& left_out);

struct DroppedPoint {
  double lat_deg = 0, lon_deg = 0;
  std::string reason;
};

// A tool orientation turned from the policy's (ShellPlanner::policyPose): about the vertical,
// tilted and rolled about the tool's axis.
struct ToolOffset {
  double yaw_deg = 0, pitch_deg = 0, roll_deg = 0;
};

// A safe data point of a shell: where the ball is on the shell, the tool orientation that
// reaches it, and the joints (nominal model) there.
struct ShellPoint {
  double lat_deg = 0, lon_deg = 0;
  ToolOffset offset;
  JointsDeg joints_deg = JointsDeg::Zero();
};

// The safe data points of a grid on one shell (the optimal design's candidates, design.hpp).
struct ShellCandidates {
  ArmConfig config;                   // the configuration that reaches the most grid points
  std::optional<ShellPoint> connect;  // nullopt: no safe pose at the connect place
  std::vector<ShellPoint> points;     // up to `orientations` per grid point
};

struct ShellSummary {
  int points = 0, vias = 0;
  double duration_s = 0;                // moves at the configured speed plus dwells
  double max_deviation_mm = 0;          // nominal radial deviation, worst over all segments
  double predicted_deflection_mm = -1;  // worst |deflection| with model error; < 0: not computed
  // Worst change of the deflection from its value at the connect pose: what the bar must absorb
  // when the shell's radius is set to the bar's length measured at the connect pose.
  double predicted_change_mm = -1;
};

struct ShellPlan {
  int shell = 1;  // 1-based number, written to the samples
  Connection connection;
  double extension_mm = 0;
  double radius_mm = 0;  // bar nominal length + extension
  ArmConfig config;
  PlanStep connect;  // where the operator attaches the bar (a "point" kind, not measured)
  std::vector<PlanStep> steps;
  std::vector<DroppedPoint> dropped;
  ShellSummary summary;
};

struct PlanSummary {
  int shells = 0, points = 0, vias = 0, dropped = 0;
  double duration_s = 0;   // robot time: moves and dwells
  double swap_time_s = 0;  // the operator's bar swaps: motion.swap_s per shell
  double cell_time_s = 0;  // what the calibration costs the cell: duration_s + swap_time_s
  double max_deviation_mm = 0;
  double predicted_deflection_mm = -1;  // worst over shells; < 0: not computed
  double predicted_change_mm = -1;      // worst over shells; < 0: not computed
  int rank = 0, expected_rank = 36;     // identification Jacobian of all the plan's points
  double condition_number = 0;          // of the column-scaled Jacobian on its identified part
  // Predicted RMS tool position error over the cell's work volume after the fit (design.hpp),
  // for the bar noise below; < 0: not computed.
  double predicted_work_volume_error_mm = -1;
  // The same over the arm's whole range (joint vectors within its limits), beside it.
  double predicted_whole_range_error_mm = -1;
  double noise_sigma_mm = 0;
};

// What a plan is for: the calibration's data, the short check that the calibrated model still
// fits the robot (docs/health-check.md), or the ISO 9283-style performance test (iso_plan.hpp,
// docs/iso9283.md). Plan files without it are calibration plans.
enum class PlanPurpose { kCalibration, kCheck, kIsoTest };
// "calibration", "check", "iso9283".
const char* planPurposeName(PlanPurpose purpose);
// The purpose named `name`, or nullopt.
std::optional<PlanPurpose> parsePlanPurpose(const std::string& name);

// The ISO 9283-style test's settings (iso_plan.hpp), kept in its plan for the report.
struct IsoTestSettings {
  int cycles = 30;         // measured cycles P1..P5, the standard's 30
  int warmup_cycles = 3;   // cycles before them, moved and measured but left out of the figures
  double spread_deg = 15;  // P2..P5 this far from P1 in latitude and longitude
};

struct Plan {
  std::string model_name;
  PlanPurpose purpose = PlanPurpose::kCalibration;
  std::optional<IsoTestSettings> iso;  // purpose kIsoTest only
  CellConfig cell;                     // the settings used
  std::vector<ShellPlan> shells;
  PlanSummary summary;
};

// One pose of a segment, with everything the safety rules look at.
struct PoseReport {
  double deviation_mm = 0;        // |ball - chuck| - radius, nominal model
  double bar_tool_angle_deg = 0;  // between the bar (ball to chuck) and the tool's backward axis
  double min_height_mm = 0;       // lowest of the flange and the wrist centre (z)
  double bar_clearance_mm = 0;    // nearest of the flange and the wrist centre to the bar
  SingularityMargins singularity;
  Eigen::Vector3d ball_mm = Eigen::Vector3d::Zero();
};

// Plans shells for one model and cell. Construction checks the settings (PlanError); planning a
// shell is independent of the others and the planner is immutable (thread-safe).
class ShellPlanner {
 public:
  ShellPlanner(const Model& model, const CellConfig& cell);

  const Model& model() const { return arm_->model(); }
  const CellConfig& cell() const { return cell_; }
  const Arm& arm() const { return *arm_; }

  ShellPlan planShell(const Connection& connection, double extension_mm, int shell_number) const;

  // Every grid point of the shell that is safe in the shell's arm configuration (chosen as
  // planShell chooses it), with up to `orientations` safe tool orientations each (the policy's
  // first, then the nearest others).
  ShellCandidates candidatePoints(const Connection& connection, double extension_mm,
                                  const GridSettings& grid, int orientations) const;

  // The shell that visits `points` in the given order from `connect` (or from the first point
  // when there is none): joints 4 and 6 unwrapped into their limits, vias where a move would
  // take the bar past the tolerance (bisection, so vias sit only where the deviation needs
  // them). Points that cannot be joined safely are dropped with the reason.
  ShellPlan joinPoints(const Connection& connection, double extension_mm, int shell_number,
                       const ArmConfig& config, const std::optional<ShellPoint>& connect,
                       std::vector<ShellPoint> points) const;

  // Re-plans what is left of `shell` for this planner's model (e.g. one refined from the data
  // measured so far): steps[0 .. next_step-1] are kept as they are; the data points from
  // next_step on keep their latitude and longitude, get new joints (numerical refinement seeded
  // with the old ones) and new vias, starting from `current_joints` (where the robot is now, on
  // the shell with the bar attached). Points that fail are dropped.
  ShellPlan replanRemaining(const ShellPlan& shell, std::size_t next_step,
                            const JointsDeg& current_joints) const;

  // The tool pose the orientation policy gives at (lat, lon) of the shell. When that pose is not
  // safe, the planner tries others: the approach turned about the vertical by `yaw_offset_deg`,
  // tilted by `pitch_offset_deg` and rolled by `roll_offset_deg`.
  Eigen::Isometry3d policyPose(const Connection& connection, double radius_mm, double lat_deg,
                               double lon_deg, double yaw_offset_deg = 0,
                               double pitch_offset_deg = 0, double roll_offset_deg = 0) const;

  PoseReport inspect(const Connection& connection, double radius_mm, const JointsDeg& q) const;
  // Empty when the pose keeps every rule (limits minus margin, singularity margins, bar-tool
  // angle, table clearance, |deviation| <= tolerance), else the first rule it breaks.
  std::string poseProblem(const Connection& connection, double radius_mm, const JointsDeg& q,
                          double tolerance_mm) const;

  // The ball positions along the joint-interpolated segment a -> b, spaced at most
  // motion.sample_step_mm apart (both ends included).
  std::vector<JointsDeg> segmentSamples(const Connection& connection, const JointsDeg& a,
                                        const JointsDeg& b) const;

  // Time of a joint-interpolated move (s), without dwell.
  double moveDuration(const JointsDeg& a, const JointsDeg& b) const;

  // Moving through vias: the first problem along the path the controller blends from `from`
  // through `steps` (the last is where it stops; robocal/kinematics/path_motion.hpp with
  // motion.blend_deg), sampled at most motion.sample_step_mm of the ball apart, and the index of
  // the step nearest it. Empty when the path is safe or has one step (no corner).
  struct BlendProblem {
    std::string problem;
    std::size_t nearest_step = 0;
  };
  BlendProblem blendedPathProblem(const Connection& c, double radius, const JointsDeg& from,
                                  const std::vector<JointsDeg>& steps, double tolerance_mm) const;

 private:
  struct Node;
  struct PointTry {
    ShellPoint point;
    std::string problem;  // empty when the point is safe
  };
  struct GridChoice {
    int config = 0;                    // arm configuration index
    std::vector<char> valid;           // per grid point (lat-major): safe in some orientation
    std::vector<std::string> problem;  // per grid point: why not, in that configuration
  };
  PointTry tryPoint(const Connection& c, double radius, double lat_deg, double lon_deg,
                    const ToolOffset& offset, const ArmConfig& config) const;
  GridChoice chooseConfig(const Connection& c, double radius, const std::vector<double>& lats,
                          const std::vector<double>& lons) const;
  std::optional<ShellPoint> connectPoint(const Connection& c, double radius,
                                         const ArmConfig& config) const;
  std::string poseProblem(const Connection& c, double radius, const JointsDeg& q,
                          double tolerance_mm, PoseReport& report) const;
  std::string problemOf(const JointsDeg& q, const PoseReport& report, double tolerance_mm) const;
  PoseReport inspectPose(const Connection& c, double radius, const JointsDeg& q,
                         const Eigen::Isometry3d& pose) const;
  // Walks the joint-interpolated move a -> b so that the ball moves at most sample_step_mm
  // between samples, calling visit(index, joints, tool pose) until it returns false (then
  // returns false). A finer try restarts at index 0. `length` (mm), when known, is the ball's
  // approximate path length.
  bool walkSegment(
      const Connection& c, const JointsDeg& a, const JointsDeg& b,
      const std::function<bool(int, const JointsDeg&, const Eigen::Isometry3d&)>& visit,
      double length = -1) const;
  bool planArc(const Connection& c, double radius, const ArmConfig& config, const Node& a,
               const Node& b, int depth, std::vector<PlanStep>& vias, double& worst,
               std::string& why) const;
  bool segmentOk(const Connection& c, double radius, const JointsDeg& a, const JointsDeg& b,
                 double tolerance_mm, double& worst, std::string& why) const;
  // The way from `a` into the point `b`: vias (planArc) to b's approach pre-point
  // (motion.approach_deg below b in every joint, checked like any via), the pre-point, so that
  // every joint moves into b in the positive direction. Without pre-points, planArc(a, b).
  bool planApproach(const Connection& c, double radius, const ArmConfig& config, const Node& a,
                    const Node& b, std::vector<PlanStep>& vias, double& worst,
                    std::string& why) const;
  // What is wrong with the approach pre-point of the point at `q` (set in `pre_q`), "" when it
  // is safe: planApproach and an optimal plan's candidates judge it the same way.
  std::string approachProblem(const Connection& c, double radius, const JointsDeg& q,
                              JointsDeg& pre_q) const;
  // Marks the vias to stop at (moving through vias) from step first_step on, the arm at `from`
  // (the connect pose when null), then sums the shell up.
  void finishShell(ShellPlan& shell, std::size_t first_step = 0,
                   const JointsDeg* from = nullptr) const;
  // Moving through vias: from step first_step on, the arm at `from`, each stretch between two
  // stops whose blended path breaks a rule stops at the via nearest the problem, until every
  // stretch is safe.
  void markBlendStops(ShellPlan& shell, std::size_t first_step, JointsDeg from) const;
  // The planned time of `step` reached from `from`: its move, and the settle at a point.
  double stepDuration(const JointsDeg& from, const PlanStep& step) const;
  Node nodeFor(const Connection& c, double radius, double lat_deg, double lon_deg,
               const Eigen::Isometry3d& pose, const JointsDeg& q) const;

  std::shared_ptr<const Arm> arm_;
  CellConfig cell_;
  Eigen::Vector3d joint1_origin_;
  Eigen::Isometry3d tool_inv_;
};

// Plans every shell of the cell: for each extension, each connection in order. Shell numbers
// count from 1 over the whole plan. Throws PlanError when the settings give no plan.
Plan planCell(const Model& model, const CellConfig& cell);

// The plan's data points as samples (lengths from the model, i.e. zero residual).
std::vector<Sample> planSamples(const Model& model, const Plan& plan);

// Rank and condition number of the identification Jacobian of the plan's points (all shells, or
// only those with the given extension when extension_mm >= 0).
struct PlanIdentifiability {
  int points = 0, rank = 0, expected_rank = 36;
  double condition_number = 0;
};
PlanIdentifiability planIdentifiability(const Model& model, const Plan& plan,
                                        double extension_mm = -1);
// The plan's summary gets the rank and condition number of all its points (what `robocal plan`
// writes and robocald's PLAN reports).
void summarizeIdentifiability(const Model& model, Plan& plan);

// Worst |bar deflection| per shell for the given true robots: the largest |true distance minus
// the radius| over the connect pose and every step, plus the shell's worst nominal deviation
// along the moves (a bound, since the model error changes little over one move). Sets
// summary.predicted_deflection_mm and predicted_change_mm (the same, relative to the deflection
// at the connect pose) of every shell and of the plan.
void predictDeflections(const Model& nominal, const std::vector<Model>& truths, Plan& plan);

// Fills the plan summary's totals from its shells (not rank or deflection).
void summarizePlan(Plan& plan);

// Where a plan's cell time goes (the motion model of summary.duration_s: each move at the cell's
// joint speed plus move_overhead_s, a stop; settle_s at each point; swap_s a shell). The parts
// add up to summary.cell_time_s.
struct CellTimeParts {
  int points = 0;
  int stops = 0;          // moves that end in a stop: points, and vias unless passed through
  double dwell_s = 0;     // settle_s at every point
  double motion_s = 0;    // the moves themselves, at the joint speed
  double stopping_s = 0;  // move_overhead_s per stop
  double swap_s = 0;      // the operator's bar swaps
  double total_s() const { return dwell_s + motion_s + stopping_s + swap_s; }
};
CellTimeParts cellTimeParts(const Plan& plan);

}  // namespace robocal
