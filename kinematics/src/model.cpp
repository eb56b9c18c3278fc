#include <robocal/kinematics/model.hpp>

#include <robocal/kinematics/units.hpp>

#include <cmath>
#include <cstdio>

namespace robocal {
namespace {

// A parameter's value in the Model (mm, deg, unitless) and in ParamVector (mm, rad, unitless).
double toInternal(ParamKind kind, double value) {
  return kind == ParamKind::kAngle ? value * kRadPerDeg : value;
}
double toInterface(ParamKind kind, double value) {
  return kind == ParamKind::kAngle ? value * kDegPerRad : value;
}
// The Model field parameter `index` holds.
double& modelField(Model& m, int index) {
  const ParamSlot s = paramSlot(index);
  return s.joint ? m.joints[s.element].*kJointFields[s.field].field
                 : m.links[s.element].*kLinkFields[s.field].field;
}
double modelField(const Model& m, int index) {
  const ParamSlot s = paramSlot(index);
  return s.joint ? m.joints[s.element].*kJointFields[s.field].field
                 : m.links[s.element].*kLinkFields[s.field].field;
}

}  // namespace

ParamVector paramSigmas(double translation_mm, double link_angle_deg, double joint_offset_deg,
                        double gain) {
  ParamVector sigma;
  for (int i = 0; i < kParamCount; ++i) {
    switch (paramKind(i)) {
      case ParamKind::kTranslation:
        sigma[i] = translation_mm;
        break;
      case ParamKind::kAngle:
        sigma[i] = (paramSlot(i).joint ? joint_offset_deg : link_angle_deg) * kRadPerDeg;
        break;
      case ParamKind::kGain:
        sigma[i] = gain;
        break;
    }
  }
  return sigma;
}

std::string paramName(int index) {
  const ParamSlot s = paramSlot(index);
  if (!s.joint) return "L" + std::to_string(s.element) + "." + kLinkFields[s.field].key;
  return "J" + std::to_string(s.element + 1) + "." + kJointFields[s.field].key;
}

const char* paramUnit(int index) {
  switch (paramKind(index)) {
    case ParamKind::kTranslation:
      return "mm";
    case ParamKind::kAngle:
      return "deg";
    case ParamKind::kGain:
      break;
  }
  return "";
}

double paramInterfaceValue(const ParamVector& params, int index) {
  return toInterface(paramKind(index), params[index]);
}

int paramIndexByName(const std::string& name) {
  for (int i = 0; i < kParamCount; ++i)
    if (paramName(i) == name) return i;
  return -1;
}

ParamVector toParams(const Model& model) {
  ParamVector p;
  for (int i = 0; i < kParamCount; ++i) p[i] = toInternal(paramKind(i), modelField(model, i));
  return p;
}

std::optional<Model> recordedNominal(const Model& calibrated) {
  if (!calibrated.provenance || !calibrated.provenance->nominal_params) return std::nullopt;
  Model nominal = withParams(calibrated, *calibrated.provenance->nominal_params);
  nominal.name = calibrated.provenance->nominal_name;
  nominal.provenance.reset();
  // The controller's model is rigid: the calibration's load, no twist (a fit identifies it).
  if (nominal.compliance) nominal.compliance->deg_per_nm = {};
  return nominal;
}

std::optional<std::string> parameterDifference(const Model& here, const Model& there) {
  const ParamVector a = toParams(here), b = toParams(there);
  for (int i = 0; i < kParamCount; ++i) {
    const double x = paramInterfaceValue(a, i), y = paramInterfaceValue(b, i);
    if (std::abs(x - y) <= 1e-6) continue;
    const std::string unit = paramUnit(i);
    const auto value = [&](double v) {
      char buf[48];
      std::snprintf(buf, sizeof buf, "%.6g", v);
      return std::string(buf) + (unit.empty() ? "" : " " + unit);
    };
    return paramName(i) + " is " + value(x) + " here, " + value(y) + " there";
  }
  return std::nullopt;
}

Model withParams(const Model& base, const ParamVector& p) {
  Model m = base;
  m.covariance.reset();
  for (int i = 0; i < kParamCount; ++i) modelField(m, i) = toInterface(paramKind(i), p[i]);
  return m;
}

Eigen::Isometry3d linkTransform(const LinkParams& l) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() << l.x_mm, l.y_mm, l.z_mm;
  t.linear() = (Eigen::AngleAxisd(l.rz_deg * kRadPerDeg, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(l.ry_deg * kRadPerDeg, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(l.rx_deg * kRadPerDeg, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return t;
}

LinkParams linkFromTransform(const Eigen::Isometry3d& t, std::string name) {
  const Eigen::Matrix3d r = t.linear();
  LinkParams l;
  l.name = std::move(name);
  l.x_mm = t.translation().x();
  l.y_mm = t.translation().y();
  l.z_mm = t.translation().z();
  l.ry_deg = std::atan2(-r(2, 0), std::hypot(r(0, 0), r(1, 0))) * kDegPerRad;
  l.rz_deg = std::atan2(r(1, 0), r(0, 0)) * kDegPerRad;
  l.rx_deg = std::atan2(r(2, 1), r(2, 2)) * kDegPerRad;
  l.rz_deg += 0.0;  // no "-0" in files
  l.ry_deg += 0.0;
  l.rx_deg += 0.0;
  return l;
}

Model modelFromStandardDH(const std::array<DHRow, kJointCount>& dh, const Eigen::Isometry3d& base,
                          const Eigen::Isometry3d& tool) {
  Model m;
  m.links[0] = linkFromTransform(base, "base");
  for (int k = 1; k <= kJointCount; ++k) {
    const DHRow& row = dh[k - 1];
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.translation() << row.a_mm, 0.0, row.d_mm;
    t.linear() =
        Eigen::AngleAxisd(row.alpha_deg * kRadPerDeg, Eigen::Vector3d::UnitX()).toRotationMatrix();
    if (k == kJointCount) t = t * tool;
    m.links[k] = linkFromTransform(t, k == kJointCount ? "tool" : "link" + std::to_string(k));
    m.joints[k - 1].name = "J" + std::to_string(k);
    m.joints[k - 1].offset_deg = row.theta_offset_deg;
    m.joints[k - 1].gain = 1.0;
  }
  m.balls_mm.fill(Eigen::Vector3d::Zero());
  m.chucks_mm.fill(Eigen::Vector3d::Zero());
  return m;
}

}  // namespace robocal
