#include <robocal/kinematics/dh.hpp>
#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/units.hpp>

#include <algorithm>
#include <cmath>
#include <random>

namespace robocal {
namespace {

struct Line {
  Eigen::Vector3d point, dir;  // dir a unit vector
};

Eigen::Vector3d footOn(const Line& line, const Eigen::Vector3d& p) {
  return line.point + line.dir * line.dir.dot(p - line.point);
}

// A frame with its z along `z` and its x along `x` made perpendicular to z.
Eigen::Isometry3d frameAt(const Eigen::Vector3d& origin, Eigen::Vector3d x,
                          const Eigen::Vector3d& z) {
  x = (x - z * z.dot(x)).normalized();
  Eigen::Isometry3d f = Eigen::Isometry3d::Identity();
  f.linear().col(0) = x;
  f.linear().col(1) = z.cross(x);
  f.linear().col(2) = z;
  f.translation() = origin;
  return f;
}

// A vector perpendicular to `z`, for when nothing else fixes x.
Eigen::Vector3d anyPerpendicular(const Eigen::Vector3d& z) {
  const Eigen::Vector3d other =
      std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  return z.cross(other).normalized();
}

// The DH row that takes frame `from` to `to` (exact when to's x axis meets from's z axis at a
// right angle; otherwise the nearest such).
DHRow rowBetween(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to) {
  const Eigen::Isometry3d rel = from.inverse() * to;
  const Eigen::Vector3d x = rel.linear().col(0), z = rel.linear().col(2);
  const Eigen::Vector3d o = rel.translation();
  DHRow r{};
  const double theta = std::atan2(x.y(), x.x());
  r.theta_offset_deg = radToDeg(theta);
  r.d_mm = o.z();
  r.a_mm = o.x() * std::cos(theta) + o.y() * std::sin(theta);
  // alpha: from z_{i-1} (0, 0, 1) to z_i about x_i.
  const Eigen::Vector3d x_dir(std::cos(theta), std::sin(theta), 0);
  r.alpha_deg = radToDeg(std::atan2(Eigen::Vector3d::UnitZ().cross(z).dot(x_dir), z.z()));
  return r;
}

Eigen::Isometry3d dhStep(const DHRow& row, double theta_rad) {
  Eigen::Isometry3d a = Eigen::Isometry3d::Identity();
  a.rotate(Eigen::AngleAxisd(theta_rad, Eigen::Vector3d::UnitZ()));
  a.translate(Eigen::Vector3d(row.a_mm, 0, row.d_mm));  // Tz(d) Tx(a): they commute
  a.rotate(Eigen::AngleAxisd(degToRad(row.alpha_deg), Eigen::Vector3d::UnitX()));
  return a;
}

}  // namespace

Eigen::Isometry3d dhToolPose(const DhTable& table, const JointsDeg& readings) {
  Eigen::Isometry3d t = table.base;
  for (int i = 0; i < kJointCount; ++i) {
    const DHRow& row = table.rows[i];
    t = t * dhStep(row, jointAngleRad(degToRad(row.theta_offset_deg), table.gains[i], readings[i]));
  }
  return t * table.tool;
}

DhTable dhFromModel(const Model& model, double parallel_tolerance_deg, int checks, unsigned seed) {
  const Kinematics kin(toParams(model));  // rigid
  const auto frames = kin.chainFrames(JointsDeg::Zero());
  // Joint k's axis (0-based k) at zero readings: the z of the frame after L(k).
  std::array<Line, kJointCount> axes;
  for (int k = 0; k < kJointCount; ++k)
    axes[k] = {frames[2 * k].translation(), frames[2 * k].linear().col(2).normalized()};

  DhTable table;
  for (int k = 0; k < kJointCount; ++k) table.gains[k] = model.joints[k].gain;
  // DH frames O_0 .. O_6: O_i's z is joint i+1's axis (O_6 turns with joint 6 alone).
  std::array<Eigen::Isometry3d, kJointCount + 1> o;
  const double sin_tol = std::sin(degToRad(parallel_tolerance_deg));
  Eigen::Vector3d base_point = axes[0].point;  // on axis 1: where O_0 goes
  Eigen::Vector3d prev_origin = axes[0].point;
  Eigen::Vector3d prev_x = anyPerpendicular(axes[0].dir);
  for (int i = 1; i < kJointCount; ++i) {  // O_i, between axes i and i+1 (1-based)
    const Line& a = axes[i - 1];
    const Line& b = axes[i];
    const Eigen::Vector3d n = a.dir.cross(b.dir);
    Eigen::Vector3d on_a, on_b;
    if (n.norm() > sin_tol) {
      // The common normal: the closest points of the two lines.
      const Eigen::Vector3d w = a.point - b.point;
      const double ad = a.dir.dot(b.dir), aw = a.dir.dot(w), bw = b.dir.dot(w);
      const double den = 1 - ad * ad;
      const double s = (ad * bw - aw) / den, t = (bw - ad * aw) / den;
      on_a = a.point + s * a.dir;
      on_b = b.point + t * b.dir;
    } else {
      table.parallel_joints.push_back(i);
      on_a = prev_origin;  // the previous frame's origin lies on axis a
      on_b = footOn(b, on_a);
    }
    Eigen::Vector3d x = on_b - on_a;
    if (x.norm() < 1e-9) x = n.norm() > 1e-12 ? n : prev_x;  // intersecting (or the same) axes
    o[i] = frameAt(on_b, x, b.dir);
    if (i == 1) base_point = on_a;
    prev_origin = on_b;
    prev_x = o[i].linear().col(0);
  }
  o[0] = frameAt(base_point, o[1].linear().col(0), axes[0].dir);
  o[kJointCount] = o[kJointCount - 1];
  table.base = o[0];
  for (int i = 1; i <= kJointCount; ++i) table.rows[i - 1] = rowBetween(o[i - 1], o[i]);
  table.tool = o[kJointCount].inverse() * frames[2 * kJointCount];

  // The table against the model.
  std::mt19937_64 rng(seed);
  table.checks = checks;
  for (int c = 0; c < checks; ++c) {
    JointsDeg q;
    for (int k = 0; k < kJointCount; ++k)
      q[k] = std::uniform_real_distribution<double>(model.joints[k].min_deg,
                                                    model.joints[k].max_deg)(rng);
    const Eigen::Isometry3d want = kin.toolPose(q), got = dhToolPose(table, q);
    table.max_position_error_mm =
        std::max(table.max_position_error_mm, (want.translation() - got.translation()).norm());
    table.max_rotation_error_deg =
        std::max(table.max_rotation_error_deg,
                 radToDeg(Eigen::AngleAxisd(want.linear().transpose() * got.linear()).angle()));
  }
  return table;
}

}  // namespace robocal
