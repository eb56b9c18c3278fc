// Compensation: the joint readings that put the real robot's tool where a target says, computed
// with the calibrated model instead of the nominal one the controller believes in
// (docs/compensation.md). Math only; no I/O.
//
// Frames, the contract of every compensation interface:
// - world: the chuck fixture's frame (the frame of the model's `chucks`);
// - tool: the last link's frame (after L6, the ball fixture's frame, where the model's `balls` are
//   given) times an optional tool centre point `tool` given in that frame.
// A pose as text is x_mm, y_mm, z_mm, rz_deg, ry_deg, rx_deg = Trans(x, y, z) Rz Ry Rx, as the
// links (linkTransform).
//
// A target is solved in the nominal model first (what the controller would be told without
// compensation; it fixes the arm configuration and each joint's 360-degree turn), then in the
// calibrated model from the nominal solution, so the corrected readings stay in that
// configuration and turn.
#pragma once

#include <robocal/kinematics/model.hpp>
#include <robocal/robot/arm.hpp>

#include <array>
#include <memory>
#include <optional>
#include <string>

namespace robocal {

// x, y, z in mm and ZYX angles in deg, as a link: Trans(x, y, z) Rz(rz) Ry(ry) Rx(rx).
Eigen::Isometry3d poseFromXyzZyx(double x_mm, double y_mm, double z_mm, double rz_deg,
                                 double ry_deg, double rx_deg);

// "x,y,z,rz,ry,rx" (mm, deg) as above; nullopt when it is not six finite numbers.
std::optional<Eigen::Isometry3d> parsePoseText(const std::string& text);

enum class CompensationStatus {
  kOk,
  kUnreachable,      // no configuration reaches the pose, or the solution did not converge
  kNearSingularity,  // solved, but within the singularity margins: small errors, large motions
  kOutsideLimits,    // solved, but no turn of some joint lies inside its limits
  // Solved, but a joint lies outside the range the calibration measured it over (the model's
  // provenance): the fit says little about the arm there.
  kOutsideMeasured,
  // Solved, but the calibrated model's predicted error there exceeds the correction it makes:
  // compensating is not known to be better than not.
  kNoGain,
};
// "ok", "unreachable", "near_singularity", "outside_limits", "outside_measured", "no_gain": the
// files' and protocol's words.
const char* compensationStatusName(CompensationStatus status);

// What a calibration may leave unidentified, at its prior size, so that a predicted error counts
// it instead of dropping it (docs/accuracy.md, "Honest extrapolation"; the twists' priors are in
// the fit's covariance, solver/compliance_fit.hpp).
struct UnidentifiedPriors {
  // A geared arm's full backlash a joint (deg): 0.005-0.02 in the literature (docs/realism.md).
  // Counted when the calibration did not design it out (no approach recorded).
  double backlash_deg = 0.01;
  // None: the covariance as the fit left it (a test of its plumbing).
  static UnidentifiedPriors none() { return {0}; }
};

struct CompensationOptions {
  Eigen::Isometry3d tool = Eigen::Isometry3d::Identity();  // TCP in the last link's frame
  // The calibrated solution must reach the target this closely, else the status says why not.
  double position_tolerance_mm = 1e-4;
  double angle_tolerance_rad = 1e-6;
  // Closer than these to a singularity (Arm::singularityMargins) is near_singularity.
  double wrist_singularity_deg = 2.0;
  double elbow_singularity_deg = 2.0;
  double shoulder_singularity_mm = 20.0;
  // A joint this far outside the range the calibration measured it over is outside_measured.
  double measured_margin_deg = 2.0;
  // Each target is reached from a pre-point this far below it in every joint, as the calibration
  // reached its points (backlash then sits on the side the joint offsets hold); 0: no approach.
  // Unset: the calibrated model's (its provenance's approach_deg).
  std::optional<double> approach_deg;
  // What the calibration left unidentified, counted in the predicted errors at this size.
  UnidentifiedPriors priors;
};

struct CompensatedTarget {
  CompensationStatus status = CompensationStatus::kUnreachable;
  std::string reason;  // why the status is not ok, in words; empty when ok
  ArmConfig config;
  Eigen::Isometry3d target = Eigen::Isometry3d::Identity();  // the desired tool pose (world)
  JointsDeg nominal_joints_deg = JointsDeg::Zero();          // the nominal model's solution
  JointsDeg joints_deg = JointsDeg::Zero();  // corrected readings (the calibrated model's)
  // 1-sigma tool position (mm) and orientation (deg) error of the calibrated model at the
  // corrected readings, from its covariance; NaN when the model has none.
  double predicted_position_error_mm = 0;
  double predicted_orientation_error_deg = 0;
  double position_residual_mm = 0;  // |calibrated tool pose - target| at joints_deg
  double angle_residual_deg = 0;
  // Each joint's direction into the target: +1 up from the pre-point, 0 when no approach is
  // assumed (CompensationOptions::approach_deg 0).
  std::array<int, kJointCount> approach{};
  JointsDeg pre_point_deg = JointsDeg::Zero();  // where the approach starts, when it is assumed
  bool hasApproach() const { return approach[0] != 0; }
  bool ok() const { return status == CompensationStatus::kOk; }
  // Reached in the calibrated model, inside the limits, away from singularities: ok, or ok but
  // where the calibration says little (outside_measured, no_gain). Work volumes and accuracy
  // figures are drawn from these, so that what the calibration did not cover shows in them.
  bool solved() const {
    return ok() || status == CompensationStatus::kOutsideMeasured ||
           status == CompensationStatus::kNoGain;
  }
  // Whether the corrected readings are given: ok, and the statuses that warn
  // (near_singularity, outside_measured, no_gain).
  bool hasJoints() const {
    return status == CompensationStatus::kOk || status == CompensationStatus::kNearSingularity ||
           status == CompensationStatus::kOutsideMeasured || status == CompensationStatus::kNoGain;
  }
};

class Compensator {
 public:
  // Throws std::invalid_argument when no arm serves a model (makeArm).
  Compensator(const Model& nominal, const Model& calibrated, CompensationOptions options = {});

  const Model& nominal() const { return nominal_->model(); }
  const Model& calibrated() const { return calibrated_->model(); }
  const Arm& nominalArm() const { return *nominal_; }
  const Arm& calibratedArm() const { return *calibrated_; }
  const CompensationOptions& options() const { return options_; }
  // The pre-point step in effect (options, else the calibrated model's), deg; 0: none.
  double approachDeg() const { return approach_deg_; }

  // A desired tool pose in the world frame, in `config`; without one, the first of the eight
  // configurations (armConfigFromIndex order) whose nominal solution is within the limits and
  // away from the singularities.
  CompensatedTarget forPose(const Eigen::Isometry3d& tool_pose,
                            std::optional<ArmConfig> config = std::nullopt) const;
  // A program's readings computed with the nominal model: the pose they mean (the nominal tool
  // pose there), reached with the calibrated model in the same configuration and turns. When
  // the two models are equal, the readings come back unchanged.
  CompensatedTarget forNominalJoints(const JointsDeg& readings_deg) const;

  // The tool pose (world frame) a model puts at these readings.
  Eigen::Isometry3d nominalToolPose(const JointsDeg& readings_deg) const;
  Eigen::Isometry3d calibratedToolPose(const JointsDeg& readings_deg) const;

  // The calibrated model's 1-sigma tool position error (mm) and orientation error (deg) at these
  // readings, from its covariance with what the fit left unidentified at its prior size
  // (UnidentifiedPriors); NaN when it has none. The position error includes the error the
  // fit found the model does not contain (ModelProvenance::unmodelled_mm), the orientation error
  // does not (a bar measures no orientation).
  double predictedPositionError(const JointsDeg& readings_deg) const;
  // The same without the backlash of targets reached from either side: what the calibration
  // itself leaves uncertain (what its correction is judged against).
  double predictedCalibrationError(const JointsDeg& readings_deg) const;
  double predictedOrientationError(const JointsDeg& readings_deg) const;

 private:
  CompensatedTarget solveCalibrated(CompensatedTarget t) const;
  double predictedPositionError(const JointsDeg& readings_deg, bool with_backlash) const;
  // An ok target outside the calibration's measured joint ranges, or where its predicted error
  // exceeds its correction, gets the status that says so.
  void judgeCoverage(CompensatedTarget& t) const;
  // A target with readings gets its approach pre-point, checked against the joint limits.
  void addApproach(CompensatedTarget& t) const;
  // The status a solution gets from the arm's IK status and the singularity margins.
  CompensationStatus classify(const Arm& ik, const IkSolution& s, std::string& reason) const;

  std::shared_ptr<const Arm> nominal_, calibrated_;
  CompensationOptions options_;
  Eigen::Isometry3d tool_inverse_;
  double approach_deg_ = 0;
  // Half a joint's prior backlash (rad) when no approach designs it out; 0 when one does.
  double unapproached_half_backlash_rad_ = 0;
  // The covariance restricted to the estimated parameters, and their indices.
  std::vector<int> estimated_;
  Eigen::MatrixXd covariance_;
};

// Position and orientation distance between two poses: |t_a - t_b| (mm) and the angle of
// R_a R_b^T (deg).
struct PoseDifference {
  double position_mm = 0;
  double angle_deg = 0;
};
PoseDifference poseDifference(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b);

}  // namespace robocal
