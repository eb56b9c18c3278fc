#include <robocal/solver/problem.hpp>

#include <robocal/kinematics/units.hpp>

#include <cmath>

namespace robocal {

BarLengthModel::BarLengthModel(const Model& fixtures, const ParamVector& p)
    : balls_mm_(fixtures.balls_mm), chucks_mm_(fixtures.chucks_mm) {
  // The same products as Kinematics' link constants: Trans * Rz * Ry * Rx.
  for (int k = 0; k < kLinkCount; ++k) {
    const int i = linkParamIndex(k);
    Link& l = links_[k];
    const Eigen::Matrix3d rz = Eigen::AngleAxisd(p[i + 3], Eigen::Vector3d::UnitZ()).matrix();
    const Eigen::Matrix3d rzy = rz * Eigen::AngleAxisd(p[i + 4], Eigen::Vector3d::UnitY());
    l.rotation = rzy * Eigen::AngleAxisd(p[i + 5], Eigen::Vector3d::UnitX());
    l.translation = p.segment<3>(i);
    l.ry_axis = rz.col(1);
    l.rx_axis = rzy.col(0);
  }
  for (int j = 0; j < kJointCount; ++j) {
    offset_rad_[j] = p[jointParamIndex(j)];
    gain_[j] = p[jointParamIndex(j) + 1];
  }
  if (fixtures.compliance && fixtures.compliance->twists())
    loaded_.emplace(withParams(fixtures, p));
}

template <bool kGradient>
double BarLengthModel::evaluate(const Sample& s, double* gradient) const {
  // Forward pass. Frame (rot, t) after L0, J1, L1, ..., J6, L6. origin[k] is where link k's
  // rotations act (the frame's translation after link k); axis[j] joint j's axis; after_joint[j]
  // the rotation of the frame after joint j (link j+1's frame before its own rotation).
  Eigen::Matrix3d rot = links_[0].rotation;
  Eigen::Vector3d t = links_[0].translation;
  std::array<Eigen::Vector3d, kLinkCount> origin;
  std::array<Eigen::Vector3d, kJointCount> axis;
  std::array<Eigen::Matrix3d, kJointCount> after_joint;
  origin[0] = t;
  const JointsDeg q = loaded_ ? loaded_->twistedReadings(s.joints_deg) : s.joints_deg;
  for (int j = 0; j < kJointCount; ++j) {
    const double theta = jointAngleRad(offset_rad_[j], gain_[j], q[j]);
    const double c = std::cos(theta), sn = std::sin(theta);
    if (kGradient) axis[j] = rot.col(2);
    const Eigen::Vector3d x = c * rot.col(0) + sn * rot.col(1);
    const Eigen::Vector3d y = c * rot.col(1) - sn * rot.col(0);
    rot.col(0) = x;
    rot.col(1) = y;
    if (kGradient) after_joint[j] = rot;
    const Link& l = links_[j + 1];
    t += rot * l.translation;
    origin[j + 1] = t;
    rot = rot * l.rotation;
  }
  const Eigen::Vector3d ball = rot * balls_mm_[s.ball_index] + t;
  const Eigen::Vector3d bar = ball - chucks_mm_[s.chuck_index];
  const double length = bar.norm();
  if (!kGradient) return length;

  // d length / d p = u . d ball / d p with u the bar's direction. A rotation about an axis through
  // o moves the ball by axis x (ball - o), so its entry is axis . ((ball - o) x u).
  const Eigen::Vector3d u = bar / length;
  for (int k = 0; k < kLinkCount; ++k) {
    const int i = linkParamIndex(k);
    const Eigen::Vector3d w = (ball - origin[k]).cross(u);
    Eigen::Vector3d along, v;
    if (k == 0) {
      along = u;
      v = w;
    } else {
      along.noalias() = after_joint[k - 1].transpose() * u;
      v.noalias() = after_joint[k - 1].transpose() * w;
    }
    gradient[i] = along.x();
    gradient[i + 1] = along.y();
    gradient[i + 2] = along.z();
    gradient[i + 3] = v.z();
    gradient[i + 4] = links_[k].ry_axis.dot(v);
    gradient[i + 5] = links_[k].rx_axis.dot(v);
    if (k < kJointCount) {
      const int o = jointParamIndex(k);
      gradient[o] = axis[k].dot(w);
      gradient[o + 1] = gradient[o] * (s.joints_deg[k] * kRadPerDeg);
    }
  }
  return length;
}

double BarLengthModel::length(const Sample& sample) const {
  return evaluate<false>(sample, nullptr);
}

double BarLengthModel::lengthGradient(const Sample& sample, double* gradient) const {
  return evaluate<true>(sample, gradient);
}

void evaluateProblem(const Model& fixtures, const ParamVector& params,
                     const std::vector<Sample>& samples, Eigen::VectorXd& residuals,
                     Eigen::MatrixXd* jacobian) {
  const BarLengthModel model(fixtures, params);
  const Eigen::Index n = static_cast<Eigen::Index>(samples.size());
  residuals.resize(n);
  if (!jacobian) {
    for (Eigen::Index i = 0; i < n; ++i)
      residuals[i] = samples[i].length_mm - model.length(samples[i]);
    return;
  }
  jacobian->resize(n, kParamCount);
  ParamRow gradient;
  for (Eigen::Index i = 0; i < n; ++i) {
    residuals[i] = samples[i].length_mm - model.lengthGradient(samples[i], gradient.data());
    jacobian->row(i) = -gradient;
  }
}

}  // namespace robocal
