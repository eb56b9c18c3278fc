#include <robocal/compensation/compensate.hpp>

#include <robocal/formats/csv.hpp>
#include <robocal/kinematics/twist.hpp>
#include <robocal/kinematics/units.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace robocal {

Eigen::Isometry3d poseFromXyzZyx(double x_mm, double y_mm, double z_mm, double rz_deg,
                                 double ry_deg, double rx_deg) {
  LinkParams p;
  p.x_mm = x_mm;
  p.y_mm = y_mm;
  p.z_mm = z_mm;
  p.rz_deg = rz_deg;
  p.ry_deg = ry_deg;
  p.rx_deg = rx_deg;
  return linkTransform(p);
}

std::optional<Eigen::Isometry3d> parsePoseText(const std::string& text) {
  const auto fields = csv::splitFields(text);
  if (fields.size() != 6) return std::nullopt;
  double v[6];
  for (int k = 0; k < 6; ++k) {
    const auto value = csv::number(fields[k]);
    if (!value) return std::nullopt;
    v[k] = *value;
  }
  return poseFromXyzZyx(v[0], v[1], v[2], v[3], v[4], v[5]);
}

const char* compensationStatusName(CompensationStatus status) {
  switch (status) {
    case CompensationStatus::kOk:
      return "ok";
    case CompensationStatus::kUnreachable:
      return "unreachable";
    case CompensationStatus::kNearSingularity:
      return "near_singularity";
    case CompensationStatus::kOutsideLimits:
      return "outside_limits";
    case CompensationStatus::kOutsideMeasured:
      return "outside_measured";
    case CompensationStatus::kNoGain:
      return "no_gain";
  }
  return "unreachable";
}

PoseDifference poseDifference(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  const Eigen::AngleAxisd rot(a.linear() * b.linear().transpose());
  return {(a.translation() - b.translation()).norm(), std::abs(rot.angle()) * kDegPerRad};
}

Compensator::Compensator(const Model& nominal, const Model& calibrated, CompensationOptions options)
    : nominal_(makeArm(nominal)),
      calibrated_(makeArm(calibrated)),
      options_(options),
      tool_inverse_(options.tool.inverse()),
      approach_deg_(options.approach_deg.value_or(
          calibrated.provenance ? calibrated.provenance->approach_deg : 0.0)) {
  if (calibrated.covariance) {
    const Eigen::MatrixXd& c = *calibrated.covariance;
    // The 54's, or the 54's and the twists' (which need the model's load): nothing else.
    if (c.rows() != c.cols() || (c.rows() != kParamCount && !hasTwistRows(c)) ||
        (hasTwistRows(c) && !calibrated.compliance))
      throw std::invalid_argument(
          "the calibrated model's covariance is neither 54 x 54 nor, with a compliance, 60 x 60");
    // The 54's, then the twists' when the fit looked for the compliance (Model::covariance).
    // Backlash not designed out: a target reached from either side has each joint off by half
    // the backlash, one way or the other (a term of its own: compensation neither causes nor
    // removes it, so its gain is judged without it).
    if (approach_deg_ <= 0)
      unapproached_half_backlash_rad_ = 0.5 * options_.priors.backlash_deg * kRadPerDeg;
    for (int i = 0; i < c.rows(); ++i)
      if (c(i, i) > 0) estimated_.push_back(i);
    const int n = static_cast<int>(estimated_.size());
    covariance_.resize(n, n);
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) covariance_(a, b) = c(estimated_[a], estimated_[b]);
  }
}

Eigen::Isometry3d Compensator::nominalToolPose(const JointsDeg& q) const {
  return nominal_->kinematics().toolPose(q) * options_.tool;
}

Eigen::Isometry3d Compensator::calibratedToolPose(const JointsDeg& q) const {
  return calibrated_->kinematics().toolPose(q) * options_.tool;
}

double Compensator::predictedPositionError(const JointsDeg& q) const {
  return predictedPositionError(q, true);
}

double Compensator::predictedCalibrationError(const JointsDeg& q) const {
  return predictedPositionError(q, false);
}

double Compensator::predictedPositionError(const JointsDeg& q, bool with_backlash) const {
  if (!calibrated().covariance) return std::numeric_limits<double>::quiet_NaN();
  const Kinematics& kin = calibrated_->kinematics();
  PositionJacobian full;
  kin.ballPositionJacobian(q, options_.tool.translation(), full);
  Eigen::MatrixXd j(3, estimated_.size());
  Eigen::Matrix<double, 3, kJointCount> twist = Eigen::Matrix<double, 3, kJointCount>::Zero();
  if (hasTwistRows(*calibrated().covariance))
    twist = twistColumns(full, RigidGravityTorque(calibrated())(q));
  for (size_t k = 0; k < estimated_.size(); ++k) {
    const int i = estimated_[k];
    if (i < kParamCount)
      j.col(k) = full.col(i);
    else
      j.col(k) = twist.col(i - kParamCount);
  }
  // The error the fit found the model does not contain (ModelProvenance::unmodelled_mm), seen by
  // the bar along one direction: sqrt(3) times it in 3D, in quadrature with the parameters' part.
  const double unmodelled_mm = calibrated().provenance ? calibrated().provenance->unmodelled_mm : 0;
  // Each joint's backlash when targets are reached from either side (no approach recorded).
  double backlash_mm2 = 0;
  if (with_backlash)
    for (int k = 0; k < kJointCount; ++k)
      backlash_mm2 +=
          (full.col(jointParamIndex(k)) * unapproached_half_backlash_rad_).squaredNorm();
  return std::sqrt(std::max(0.0, (j * covariance_ * j.transpose()).trace()) +
                   3 * unmodelled_mm * unmodelled_mm + backlash_mm2);
}

double Compensator::predictedOrientationError(const JointsDeg& q) const {
  if (!calibrated().covariance) return std::numeric_limits<double>::quiet_NaN();
  // The orientation's Jacobian by central differences: 2 poses per estimated parameter, cheap
  // next to the IK (the tool point does not change the orientation).
  const ParamVector p0 = calibrated_->kinematics().params();
  const Eigen::Matrix3d r0 = calibrated_->kinematics().toolPose(q).linear();
  constexpr double kStep = 1e-6;  // mm, rad, gain or deg/(N m): above rounding, below curvature
  Eigen::MatrixXd j(3, estimated_.size());
  for (size_t k = 0; k < estimated_.size(); ++k) {
    Model plus = calibrated_->model(), minus = plus;
    const int i = estimated_[k];
    if (i < kParamCount) {
      ParamVector p_plus = p0, p_minus = p0;
      p_plus[i] += kStep;
      p_minus[i] -= kStep;
      plus = withParams(plus, p_plus);
      minus = withParams(minus, p_minus);
    } else {  // a twist, deg/(N m)
      plus.compliance->deg_per_nm[i - kParamCount] += kStep;
      minus.compliance->deg_per_nm[i - kParamCount] -= kStep;
    }
    const Eigen::Matrix3d rp = Kinematics(plus).toolPose(q).linear();
    const Eigen::Matrix3d rm = Kinematics(minus).toolPose(q).linear();
    const Eigen::AngleAxisd dp(rp * r0.transpose()), dm(rm * r0.transpose());
    j.col(k) = (dp.axis() * dp.angle() - dm.axis() * dm.angle()) / (2 * kStep);
  }
  return std::sqrt(std::max(0.0, (j * covariance_ * j.transpose()).trace())) * kDegPerRad;
}

CompensationStatus Compensator::classify(const Arm& ik, const IkSolution& s,
                                         std::string& reason) const {
  switch (s.status) {
    case IkStatus::kUnreachable:
      reason = "out of the arm's reach";
      return CompensationStatus::kUnreachable;
    case IkStatus::kNoConvergence:
      reason = "the inverse kinematics did not converge in this configuration";
      return CompensationStatus::kUnreachable;
    case IkStatus::kSingular:
      reason = "at a singularity";
      return CompensationStatus::kNearSingularity;
    case IkStatus::kOutsideLimits: {
      // Which joint, where, against which limits: the operator can move the target or the limits.
      std::ostringstream which;
      which.precision(4);
      const Model& m = ik.model();
      for (int j = 0; j < kJointCount && which.tellp() == 0; ++j)
        if (s.joints_deg[j] < m.joints[j].min_deg || s.joints_deg[j] > m.joints[j].max_deg)
          which << "joint " << j + 1 << " at " << s.joints_deg[j] << " deg is outside its limits ("
                << m.joints[j].min_deg << " to " << m.joints[j].max_deg << " deg) in every turn";
      reason = which.tellp() > 0 ? which.str() : "a joint is outside its limits in every turn";
      return CompensationStatus::kOutsideLimits;
    }
    case IkStatus::kOk:
      break;
  }
  const SingularityMargins m = ik.singularityMargins(s.joints_deg);
  std::ostringstream why;
  why.precision(3);
  if (m.wrist_deg < options_.wrist_singularity_deg)
    why << "joint 5 is " << m.wrist_deg << " deg from the wrist singularity";
  else if (m.elbow_deg < options_.elbow_singularity_deg)
    why << "the elbow is " << m.elbow_deg << " deg from straight";
  else if (m.shoulder_mm < options_.shoulder_singularity_mm)
    why << "the wrist centre is " << m.shoulder_mm << " mm from joint 1's axis plane";
  reason = why.str();
  return reason.empty() ? CompensationStatus::kOk : CompensationStatus::kNearSingularity;
}

CompensatedTarget Compensator::forPose(const Eigen::Isometry3d& tool_pose,
                                       std::optional<ArmConfig> config) const {
  const Eigen::Isometry3d flange = tool_pose * tool_inverse_;
  CompensatedTarget best;
  best.target = tool_pose;
  best.reason = "out of the arm's reach in every configuration";
  for (int i = 0; i < kArmConfigCount; ++i) {
    const ArmConfig c = config ? *config : armConfigFromIndex(i);
    const IkSolution s = nominal_->solve(flange, c);
    CompensatedTarget t;
    t.target = tool_pose;
    t.config = c;
    t.nominal_joints_deg = s.joints_deg;
    t.joints_deg = s.joints_deg;
    t.status = classify(*nominal_, s, t.reason);
    // Keep the most useful answer: ok, else a solution with a reason, else unreachable.
    if (t.ok()) return solveCalibrated(t);
    if (t.status != CompensationStatus::kUnreachable &&
        best.status == CompensationStatus::kUnreachable)
      best = t;
    if (config) break;
  }
  if (best.status == CompensationStatus::kNearSingularity ||
      best.status == CompensationStatus::kOutsideLimits) {
    // Still give the corrected readings; the status warns.
    const std::string why = best.reason;
    const CompensationStatus status = best.status;
    best = solveCalibrated(best);
    if (best.ok() || best.status == status) {
      best.status = status;
      best.reason = "nominal solution: " + why;
    }
  }
  if (config && best.status == CompensationStatus::kUnreachable)
    best.reason = "out of reach in " + armConfigName(*config);
  return best;
}

CompensatedTarget Compensator::forNominalJoints(const JointsDeg& q) const {
  CompensatedTarget t;
  t.target = nominalToolPose(q);
  t.config = nominal_->configOf(q);
  t.nominal_joints_deg = q;
  t.joints_deg = q;
  return solveCalibrated(t);
}

CompensatedTarget Compensator::solveCalibrated(CompensatedTarget t) const {
  const Eigen::Isometry3d flange = t.target * tool_inverse_;
  const IkSolution s = calibrated_->refine(flange, t.config, t.nominal_joints_deg);
  t.joints_deg = s.joints_deg;
  t.status = classify(*calibrated_, s, t.reason);
  const PoseDifference d = poseDifference(calibratedToolPose(t.joints_deg), t.target);
  t.position_residual_mm = d.position_mm;
  t.angle_residual_deg = d.angle_deg;
  if (t.status != CompensationStatus::kUnreachable &&
      (d.position_mm > options_.position_tolerance_mm ||
       d.angle_deg > options_.angle_tolerance_rad * kDegPerRad)) {
    std::ostringstream why;
    why.precision(3);
    why << "the calibrated solution misses the target by " << d.position_mm << " mm and "
        << d.angle_deg << " deg";
    t.status = CompensationStatus::kUnreachable;
    t.reason = why.str();
  }
  t.predicted_position_error_mm = predictedPositionError(t.joints_deg);
  t.predicted_orientation_error_deg = predictedOrientationError(t.joints_deg);
  if (t.ok()) judgeCoverage(t);
  if (t.hasJoints()) addApproach(t);
  return t;
}

void Compensator::addApproach(CompensatedTarget& t) const {
  if (approach_deg_ <= 0) return;
  t.approach.fill(1);
  t.pre_point_deg = t.joints_deg.array() - approach_deg_;
  for (int j = 0; j < kJointCount; ++j) {
    const JointParams& joint = calibrated().joints[j];
    if (t.pre_point_deg[j] >= joint.min_deg) continue;
    std::ostringstream why;
    why.precision(4);
    why << "its approach pre-point puts joint " << j + 1 << " at " << t.pre_point_deg[j]
        << " deg, below its limit " << joint.min_deg << " deg";
    t.status = CompensationStatus::kOutsideLimits;
    t.reason = why.str();
    t.approach.fill(0);  // no readings are given: nothing to approach
    return;
  }
}

void Compensator::judgeCoverage(CompensatedTarget& t) const {
  std::ostringstream why;
  why.precision(4);
  const auto& provenance = calibrated().provenance;
  if (provenance && provenance->measured_joints_deg) {
    for (int j = 0; j < kJointCount; ++j) {
      const auto& [lo, hi] = (*provenance->measured_joints_deg)[j];
      const double q = t.joints_deg[j];
      if (q >= lo - options_.measured_margin_deg && q <= hi + options_.measured_margin_deg)
        continue;
      why << "joint " << j + 1 << " at " << q << " deg, outside the " << lo << " to " << hi
          << " deg the calibration measured it over";
      t.status = CompensationStatus::kOutsideMeasured;
      t.reason = why.str();
      return;
    }
  }
  // Not compensating leaves the tool where the calibrated model puts the nominal readings.
  const double correction_mm =
      (calibratedToolPose(t.nominal_joints_deg).translation() - t.target.translation()).norm();
  // The calibration's own uncertainty against its correction: backlash not designed out is
  // there with or without compensating.
  const double calibration_mm = predictedCalibrationError(t.joints_deg);
  if (calibration_mm > correction_mm) {
    why << "the predicted error, " << calibration_mm << " mm, exceeds the " << correction_mm
        << " mm correction";
    t.status = CompensationStatus::kNoGain;
    t.reason = why.str();
  }
}

}  // namespace robocal
