// The 54-parameter Sheth-Uicker model of a six-revolute robot (docs/model-format.md).
//
//   T = L0 * J1 * L1 * J2 * L2 * ... * J6 * L6
//   L_k = Trans(x, y, z) * Rz(rz) * Ry(ry) * Rx(rx)
//   J_k = Rz(offset + gain * reading)
//
// The Model struct holds the values as a person reads them (mm, deg). The solver works on a
// flat parameter vector (ParamVector) in mm, radians and unitless gains; only this module
// converts between the two.
#pragma once

#include <robocal/kinematics/units.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace robocal {

inline constexpr int kLinkCount = 7;
inline constexpr int kJointCount = 6;
inline constexpr int kBallCount = 3;
inline constexpr int kChuckCount = 3;

struct LinkParams {
  std::string name;
  double x_mm = 0, y_mm = 0, z_mm = 0;
  double rz_deg = 0, ry_deg = 0, rx_deg = 0;
};

struct JointParams {
  std::string name;
  double offset_deg = 0;
  double gain = 1.0;
  double min_deg = -180;  // limits of the joint reading, not of theta
  double max_deg = 180;
  // The joint's rated speed and torque, for other tools (URDF's velocity and effort); 0: not
  // known. robocal's own motion does not use them (the cell's motion section sets its speed).
  double velocity_deg_per_s = 0;
  double effort_nm = 0;
};
// The largest rated speed and torque a model file holds (a bound against nonsense, not a robot's).
inline constexpr double kMaxVelocityDegPerS = 1e5;
inline constexpr double kMaxEffortNm = 1e6;

// The parameter layout, as data. Every link holds the parameters of kLinkFields and every joint
// those of kJointFields, each naming its Model field, its key in model files and in parameter
// names ("L3.ry", "J2.offset"), and its kind. ParamVector holds them in chain order,
// L0(x,y,z,rz,ry,rx) J1(offset,gain) L1(...) ... J6 L6, translations in mm, angles in radians
// (the Model's fields in deg), gains unitless. toParams, withParams, the model file, the names,
// units and sigmas all read these tables: a new term is an entry here (with the value older
// files stand for, `absent`) plus its Jacobian columns (Kinematics::ballJacobian,
// Problem::residualsAndJacobian) and, if it changes the joint angle, jointAngleRad below.
enum class ParamKind { kTranslation, kAngle, kGain };
template <typename Params>
struct ParamField {
  const char* key;
  ParamKind kind;
  double Params::*field;
  double absent;  // the value of a file that does not have the key; NaN: the key is required
};
inline constexpr double kRequired = std::numeric_limits<double>::quiet_NaN();
inline constexpr std::array<ParamField<LinkParams>, 6> kLinkFields = {{
    {"x", ParamKind::kTranslation, &LinkParams::x_mm, kRequired},
    {"y", ParamKind::kTranslation, &LinkParams::y_mm, kRequired},
    {"z", ParamKind::kTranslation, &LinkParams::z_mm, kRequired},
    {"rz", ParamKind::kAngle, &LinkParams::rz_deg, kRequired},
    {"ry", ParamKind::kAngle, &LinkParams::ry_deg, kRequired},
    {"rx", ParamKind::kAngle, &LinkParams::rx_deg, kRequired},
}};
inline constexpr std::array<ParamField<JointParams>, 2> kJointFields = {{
    {"offset", ParamKind::kAngle, &JointParams::offset_deg, kRequired},
    {"gain", ParamKind::kGain, &JointParams::gain, kRequired},
}};
inline constexpr int kLinkParamCount = static_cast<int>(kLinkFields.size());
inline constexpr int kJointParamCount = static_cast<int>(kJointFields.size());
inline constexpr int kParamCount = kLinkCount * kLinkParamCount + kJointCount * kJointParamCount;
static_assert(kParamCount == 54);

// Gravity compliance (gravity.hpp has the torque): what gravity pulls on, the bodies moved by
// joints 1..6 and the payload at the tool.
struct GravityLoad {
  // Masses (kg) of the bodies moved by joints 1..6 and their centres of mass in the frame after
  // that joint's link (after L_k, as Corke's mdl_puma560 tabulates them in the DH link frames).
  std::array<double, kJointCount> link_mass_kg{};
  std::array<Eigen::Vector3d, kJointCount> link_com_mm = zeros();
  // The payload at the tool (the ball fixture while calibrating, the work tool after): mass and
  // centre of mass in the last link's frame.
  double payload_kg = 0;
  Eigen::Vector3d payload_com_mm = Eigen::Vector3d::Zero();
  // Gravity in the world (chuck fixture) frame, a unit vector: down.
  Eigen::Vector3d gravity_direction = -Eigen::Vector3d::UnitZ();

  bool operator==(const GravityLoad&) const = default;
  static std::array<Eigen::Vector3d, kJointCount> zeros() {
    std::array<Eigen::Vector3d, kJointCount> z;
    z.fill(Eigen::Vector3d::Zero());
    return z;
  }
};

// Joint twist per N m of gravity torque, and the load that makes the torque.
struct JointCompliance {
  GravityLoad load;
  std::array<double, kJointCount> deg_per_nm{};
  bool operator==(const JointCompliance&) const = default;
  bool twists() const {
    for (double c : deg_per_nm)
      if (c != 0) return true;
    return false;
  }
};

// Where a calibrated model came from: the fit that made it (docs/model-format.md, "provenance").
// Written with every calibrated model; carried unchanged through a read and a write; absent from
// nominal models and from files older than it.
struct ModelProvenance {
  std::string run_id;        // the robocald run, "" when the fit was not of a run
  std::string date_utc;      // when the model was made, ISO 8601: 2026-12-01T20:42:54Z
  std::string nominal_name;  // the starting model's name
  std::vector<std::string> samples_files;
  std::size_t samples = 0;  // samples fitted
  double rms_mm = 0;        // RMS residual of the fit
  int rank = 0;             // parameters estimated
  int expected_rank = 0;    // independent parameters of the robot (36 for six revolute joints)
  std::string robocal_version;
  std::vector<std::string> warnings;  // the fit's problems, when the model was written despite them
  // The starting model's 54 parameters (ParamVector units). The nominal is the calibrated model's
  // names, limits and fixtures with these: recordedNominal gives it, so compensate and accuracy
  // use the controller's model the calibration started from, and refuse another. Absent from
  // files older than it.
  std::optional<Eigen::Matrix<double, kParamCount, 1>> nominal_params;
  // The range of each joint's readings over the fitted samples, {min, max} in deg: where the
  // model was measured. Compensation flags targets outside it. Absent from older files.
  std::optional<std::array<std::array<double, 2>, kJointCount>> measured_joints_deg;
  // Every fitted point was reached moving up by this much in each joint (the plan's
  // motion.approach_deg), so the joint offsets hold the backlash of that side: compensate writes
  // its targets the same way. 0: the points were reached from either side (older files too).
  double approach_deg = 0;
  // The error the fit found that the model does not contain, RMS along the bar, in mm (the
  // adequacy test: Adequacy::unmodelled_bar_mm). A bar sees one direction of a position error:
  // the predicted position errors add sqrt(3) times it in quadrature, so a model with error it
  // cannot explain does not promise the accuracy of one without. 0: none found (older files too).
  double unmodelled_mm = 0;
};

struct Model {
  std::string name;
  std::optional<ModelProvenance> provenance;
  // The calibration's parameter covariance (54 x 54, ParamVector units: mm, rad, gain), zero rows
  // and columns for parameters that were not estimated; files hold it in mm and deg
  // (docs/model-format.md, "covariance"). When the fit looked for the compliance, 60 x 60: each
  // joint's twist (deg/(N m)) after the 54, at twistCovarianceIndex. Absent from nominal models;
  // withParams drops it.
  std::optional<Eigen::MatrixXd> covariance;
  // Gravity compliance of the joints (docs/model-format.md, "compliance"): Kinematics(model)
  // evaluates the model at the readings twisted by it. Absent: a rigid arm (and older files).
  std::optional<JointCompliance> compliance;
  std::array<LinkParams, kLinkCount> links;
  std::array<JointParams, kJointCount> joints;
  std::array<Eigen::Vector3d, kBallCount> balls_mm;    // in the last link's frame (after L6)
  std::array<Eigen::Vector3d, kChuckCount> chucks_mm;  // in the global (chuck fixture) frame
};

using ParamVector = Eigen::Matrix<double, kParamCount, 1>;
using JointsDeg = Eigen::Matrix<double, kJointCount, 1>;  // controller readings, degrees

// Where the layout puts things in ParamVector: the first parameter of link 0..6 and of joint
// 0..5 (its kLinkFields or kJointFields follow in order), and the one an entry describes.
constexpr int linkParamIndex(int link) {
  return link * (kLinkParamCount + kJointParamCount);
}
constexpr int jointParamIndex(int joint /*0-based*/) {
  return linkParamIndex(joint) + kLinkParamCount;
}
struct ParamSlot {
  bool joint;   // a joint's parameter (kJointFields), else a link's (kLinkFields)
  int element;  // link 0..6 or joint 0..5
  int field;    // index into kLinkFields or kJointFields
};
constexpr ParamSlot paramSlot(int index) {
  constexpr int block = kLinkParamCount + kJointParamCount;
  const int within = index % block;
  if (within < kLinkParamCount) return {false, index / block, within};
  return {true, index / block, within - kLinkParamCount};
}
// The parameter of that link's (or joint's) field named `key`; -1 when none has it.
constexpr int paramIndex(bool joint, int element, std::string_view key) {
  if (joint) {
    for (int f = 0; f < kJointParamCount; ++f)
      if (key == kJointFields[f].key) return jointParamIndex(element) + f;
  } else {
    for (int f = 0; f < kLinkParamCount; ++f)
      if (key == kLinkFields[f].key) return linkParamIndex(element) + f;
  }
  return -1;
}
constexpr ParamKind paramKind(int index) {
  const ParamSlot s = paramSlot(index);
  return s.joint ? kJointFields[s.field].kind : kLinkFields[s.field].kind;
}
// The order the link transform (Trans(x, y, z) Rz Ry Rx), the joint angle and their Jacobian
// columns are written for, in Kinematics and in the solver's BarLengthModel: a field added to the
// layout needs its columns there, and this check tells which code to look at.
static_assert(paramIndex(false, 0, "x") == 0 && paramIndex(false, 0, "z") == 2 &&
              paramIndex(false, 0, "rz") == 3 && paramIndex(false, 0, "ry") == 4 &&
              paramIndex(false, 0, "rx") == 5 && kLinkParamCount == 6);
static_assert(paramIndex(true, 0, "offset") == jointParamIndex(0) &&
              paramIndex(true, 0, "gain") == jointParamIndex(0) + 1 && kJointParamCount == 2);

// Model::covariance's row of joint j's (0-based) twist, when it has them: after the 54.
constexpr int twistCovarianceIndex(int joint) {
  return kParamCount + joint;
}

// The joint model, in one place: a joint turns to offset + gain * reading, the angle in radians
// for the controller's reading in degrees (offset in radians, gain unitless, as in ParamVector).
// Forward kinematics, the fit's bar-length model, the DH export and the closed-form IK all go
// through these two; jointReadingDeg is the inverse.
constexpr double jointAngleRad(double offset_rad, double gain, double reading_deg) {
  return offset_rad + gain * reading_deg * kRadPerDeg;
}
constexpr double jointReadingDeg(double offset_rad, double gain, double angle_rad) {
  return (angle_rad - offset_rad) * kDegPerRad / gain;
}
// One sigma per parameter (internal units) from a sigma per kind in interface units: link
// translations (mm), link angles (deg), joint offsets (deg), joint gains (unitless). The
// simulator's perturbation and the daemon's centring prior share it.
ParamVector paramSigmas(double translation_mm, double link_angle_deg, double joint_offset_deg,
                        double gain);
// "L0.x", "L3.ry", "J1.offset", "J6.gain".
std::string paramName(int index);
// Unit of the parameter at the interfaces: "mm", "deg" or "" (gain).
const char* paramUnit(int index);
// Value of parameter `index` of `params` in interface units (mm, deg, unitless).
double paramInterfaceValue(const ParamVector& params, int index);
// Finds a parameter by its name; -1 when no parameter has it.
int paramIndexByName(const std::string& name);

ParamVector toParams(const Model& model);
// A copy of `base` (names, limits, balls, chucks, compliance) with its 54 parameters replaced and
// no covariance (it belongs to the parameters it came with).
Model withParams(const Model& base, const ParamVector& params);

// The nominal a calibrated model started from (its provenance's nominal_params), named as it was,
// rigid (a compliance's load kept, its twist zero); empty for a nominal model and for a
// calibrated file older than the record.
std::optional<Model> recordedNominal(const Model& calibrated);
// Where two models' 54 parameters differ by more than rounding (1e-6 mm, deg or gain), the first
// such parameter in words ("L2.x is 431.8 mm here, 431.9 mm there"); empty when they agree.
std::optional<std::string> parameterDifference(const Model& here, const Model& there);

Eigen::Isometry3d linkTransform(const LinkParams& link);
// Inverse of linkTransform: x, y, z, and ZYX Euler angles rz in (-180, 180], ry in [-90, 90].
LinkParams linkFromTransform(const Eigen::Isometry3d& transform, std::string name = {});

// One row of a standard Denavit-Hartenberg table: Rz(theta) Tz(d) Tx(a) Rx(alpha).
struct DHRow {
  double d_mm, a_mm, alpha_deg, theta_offset_deg;
};
// Sheth-Uicker model equivalent to a standard DH chain: L0 = base, L_k = Tz(d_k) Tx(a_k)
// Rx(alpha_k) for k = 1..5, L6 = Tz(d_6) Tx(a_6) Rx(alpha_6) * tool; joint offsets from the table,
// gains 1.
Model modelFromStandardDH(const std::array<DHRow, kJointCount>& dh, const Eigen::Isometry3d& base,
                          const Eigen::Isometry3d& tool);

}  // namespace robocal
