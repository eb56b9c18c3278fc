#include <catch2/catch.hpp>

#include "joints.hpp"

#include <robocal/kinematics/ik.hpp>
#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/units.hpp>
#include <robocal/robot/puma560.hpp>

#include <random>

using namespace robocal;

namespace {

using test::deg;

// Corke's PUMA 560 chain with no base or tool transform, as his toolbox computes it.
Kinematics corkeChain() {
  return Kinematics(modelFromStandardDH(puma560CorkeDH(), Eigen::Isometry3d::Identity(),
                                        Eigen::Isometry3d::Identity()));
}

JointsDeg randomJoints(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-170.0, 170.0);
  JointsDeg q;
  for (int j = 0; j < kJointCount; ++j) q[j] = u(rng);
  return q;
}

}  // namespace

TEST_CASE("forward kinematics matches Corke's published PUMA 560 poses") {
  const Kinematics kin = corkeChain();
  // qz: all zero. Robotics Toolbox: p560.fkine(qz) = identity rotation at (0.4521, -0.1500, 0.4318)
  // m.
  const Eigen::Isometry3d tz = kin.toolPose(deg(0, 0, 0, 0, 0, 0));
  CHECK(tz.translation().x() == Approx(452.1).margin(1e-9));
  CHECK(tz.translation().y() == Approx(-150.05).margin(1e-9));
  CHECK(tz.translation().z() == Approx(431.8).margin(1e-9));
  CHECK(tz.linear().isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  // qr = [0 90 -90 0 0 0]: the arm straight up, (0.0203, -0.1500, 0.8636) m.
  const Eigen::Isometry3d tr = kin.toolPose(deg(0, 90, -90, 0, 0, 0));
  CHECK(tr.translation().x() == Approx(20.3).margin(1e-9));
  CHECK(tr.translation().y() == Approx(-150.05).margin(1e-9));
  CHECK(tr.translation().z() == Approx(863.6).margin(1e-9));
  // qn = [0 45 180 0 45 0], the "nominal table top" pose: (0.5963, -0.1501, -0.0144) m with the
  // tool's z axis along the base's x axis.
  const Eigen::Isometry3d tn = kin.toolPose(deg(0, 45, 180, 0, 45, 0));
  CHECK(tn.translation().x() == Approx(596.3).margin(0.05));
  CHECK(tn.translation().y() == Approx(-150.05).margin(0.05));
  CHECK(tn.translation().z() == Approx(-14.4).margin(0.05));
  CHECK(tn.linear().col(2).isApprox(Eigen::Vector3d::UnitX(), 1e-9));
}

TEST_CASE("a model built from the DH table reproduces the DH product") {
  std::mt19937_64 rng(3);
  const auto dh = puma560DH();
  const Kinematics kin(
      modelFromStandardDH(dh, Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity()));
  for (int n = 0; n < 20; ++n) {
    const JointsDeg q = randomJoints(rng);
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    for (int j = 0; j < kJointCount; ++j)
      t = t * Eigen::AngleAxisd(q[j] * kRadPerDeg, Eigen::Vector3d::UnitZ()) *
          Eigen::Translation3d(0, 0, dh[j].d_mm) * Eigen::Translation3d(dh[j].a_mm, 0, 0) *
          Eigen::AngleAxisd(dh[j].alpha_deg * kRadPerDeg, Eigen::Vector3d::UnitX());
    CHECK(kin.toolPose(q).matrix().isApprox(t.matrix(), 1e-12));
  }
}

TEST_CASE("link transforms survive the round trip through x, y, z, rz, ry, rx") {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> angle(-179.0, 179.0), tilt(-89.0, 89.0);
  for (int n = 0; n < 50; ++n) {
    LinkParams l{"l", 10.0 * n, -3.0, 7.5, angle(rng), tilt(rng), angle(rng)};
    const LinkParams back = linkFromTransform(linkTransform(l));
    CHECK(back.x_mm == Approx(l.x_mm));
    CHECK(back.rz_deg == Approx(l.rz_deg).margin(1e-9));
    CHECK(back.ry_deg == Approx(l.ry_deg).margin(1e-9));
    CHECK(back.rx_deg == Approx(l.rx_deg).margin(1e-9));
  }
}

TEST_CASE("parameter vector layout, names and units") {
  const Model m = puma560NominalModel();
  const ParamVector p = toParams(m);
  CHECK(paramName(0) == "L0.x");
  CHECK(paramName(6) == "J1.offset");
  CHECK(paramName(7) == "J1.gain");
  CHECK(paramName(kParamCount - 1) == "L6.rx");
  CHECK(std::string(paramUnit(jointParamIndex(2))) == "deg");
  CHECK(std::string(paramUnit(jointParamIndex(2) + 1)).empty());
  CHECK(paramIndexByName("J6.offset") == jointParamIndex(5));
  CHECK(paramIndexByName("nope") == -1);
  CHECK(p[linkParamIndex(0)] == Approx(m.links[0].x_mm));
  CHECK(toParams(withParams(m, p)).isApprox(p));
  // The layout's table puts each parameter in the Model field its name says, in its units.
  const auto changed = [&](const char* name, double step) {
    ParamVector q = p;
    q[paramIndexByName(name)] += step;
    return withParams(m, q);
  };
  CHECK(changed("L3.ry", 0.01).links[3].ry_deg == Approx(m.links[3].ry_deg + 0.01 * 180 / M_PI));
  CHECK(changed("L6.z", 0.5).links[6].z_mm == Approx(m.links[6].z_mm + 0.5));
  CHECK(changed("J2.gain", 1e-3).joints[1].gain == Approx(m.joints[1].gain + 1e-3));
  CHECK(changed("J4.offset", 0.01).joints[3].offset_deg ==
        Approx(m.joints[3].offset_deg + 0.01 * 180 / M_PI));
  CHECK(changed("J4.offset", 0.01).joints[2].offset_deg == m.joints[2].offset_deg);
  for (int i = 0; i < kParamCount; ++i) {
    const ParamSlot slot = paramSlot(i);
    CHECK(paramIndex(slot.joint, slot.element,
                     slot.joint ? kJointFields[slot.field].key : kLinkFields[slot.field].key) == i);
  }
}

TEST_CASE("analytic Jacobians match central differences at random poses") {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 1.0);
  const Model nominal = puma560NominalModel();
  for (int trial = 0; trial < 10; ++trial) {
    // A generic model: every parameter perturbed, so no column is special by accident.
    ParamVector p = toParams(nominal);
    for (int i = 0; i < kParamCount; ++i)
      p[i] += (paramKind(i) == ParamKind::kTranslation ? 2.0 : 0.02) * noise(rng);
    const Kinematics kin(p);
    const JointsDeg q = randomJoints(rng);
    const Eigen::Vector3d ball = nominal.balls_mm[trial % kBallCount];
    const Eigen::Vector3d chuck = nominal.chucks_mm[(trial + 1) % kChuckCount];

    ParamRow analytic;
    const double length = kin.barLengthGradient(q, ball, chuck, analytic);
    CHECK(length == Approx(kin.barLength(q, ball, chuck)).epsilon(1e-14));
    PositionJacobian pos_jac;
    kin.ballPositionJacobian(q, ball, pos_jac);
    for (int i = 0; i < kParamCount; ++i) {
      const double h = paramKind(i) == ParamKind::kTranslation ? 1e-4 : 1e-7;
      ParamVector plus = p, minus = p;
      plus[i] += h;
      minus[i] -= h;
      const double numeric = (Kinematics(plus).barLength(q, ball, chuck) -
                              Kinematics(minus).barLength(q, ball, chuck)) /
                             (2 * h);
      INFO(paramName(i));
      CHECK(analytic[i] == Approx(numeric).epsilon(1e-6).margin(1e-6 * analytic.norm()));
      const Eigen::Vector3d numeric_pos =
          (Kinematics(plus).ballPosition(q, ball) - Kinematics(minus).ballPosition(q, ball)) /
          (2 * h);
      CHECK((pos_jac.col(i) - numeric_pos).norm() <= 1e-6 * std::max(1.0, numeric_pos.norm()));
    }
  }
}

TEST_CASE("joint Jacobian matches central differences of the tool pose") {
  const Kinematics kin(puma560NominalModel());
  const JointsDeg q = deg(10, 40, -160, 30, 50, -20);
  const Eigen::Vector3d point(60, 0, 90);
  const JointJacobian jac = kin.jointJacobian(q, point);
  for (int j = 0; j < kJointCount; ++j) {
    const double h_deg = 1e-5;
    JointsDeg plus = q, minus = q;
    plus[j] += h_deg;
    minus[j] -= h_deg;
    const Eigen::Vector3d dp =
        (kin.toolPose(plus) * point - kin.toolPose(minus) * point) / (2 * h_deg * kRadPerDeg);
    CHECK((jac.block<3, 1>(0, j) - dp).norm() < 1e-5 * std::max(1.0, dp.norm()));
  }
}

TEST_CASE("numerical IK recovers random reachable poses") {
  std::mt19937_64 rng(17);
  const Model m = puma560NominalModel();
  const Kinematics kin(m);
  std::normal_distribution<double> small(0.0, 8.0);
  int solved = 0;
  for (int n = 0; n < 30; ++n) {
    JointsDeg q = deg(0, 40, -170, 20, 45, 10);
    for (int j = 0; j < kJointCount; ++j) q[j] += small(rng) * 2;
    const Eigen::Isometry3d target = kin.toolPose(q);
    JointsDeg seed = q;
    for (int j = 0; j < kJointCount; ++j) seed[j] += small(rng);
    const auto found = solveIk(kin, target, seed);
    if (!found) continue;
    ++solved;
    const Eigen::Isometry3d got = kin.toolPose(*found);
    CHECK((got.translation() - target.translation()).norm() < 1e-6);
    CHECK(got.linear().isApprox(target.linear(), 1e-9));
  }
  CHECK(solved >= 27);
}

TEST_CASE("IK reports an unreachable pose instead of returning garbage") {
  const Kinematics kin(puma560NominalModel());
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation() << 3000, 0, 0;
  CHECK_FALSE(solveIk(kin, far, deg(0, 40, -170, 0, 45, 0)).has_value());
}

TEST_CASE("joint limits with margin") {
  const Model m = puma560NominalModel();
  CHECK(withinLimits(m, deg(0, 0, 0, 0, 30, 0)));
  CHECK_FALSE(withinLimits(m, deg(0, 0, 0, 0, 101, 0)));
  CHECK_FALSE(withinLimits(m, deg(0, 0, 0, 0, 96, 0), 5.0));
  CHECK(withinLimits(m, deg(0, 0, 0, 0, 94, 0), 5.0));
}

TEST_CASE("paramSigmas: one sigma per kind, angles in radians", "[kinematics]") {
  const robocal::ParamVector s = robocal::paramSigmas(0.2, 0.02, 0.05, 0.0005);
  CHECK(s[robocal::paramIndexByName("L0.x")] == 0.2);
  CHECK(s[robocal::paramIndexByName("L3.rz")] == Approx(0.02 * robocal::kRadPerDeg));
  CHECK(s[robocal::paramIndexByName("J2.offset")] == Approx(0.05 * robocal::kRadPerDeg));
  CHECK(s[robocal::paramIndexByName("J6.gain")] == 0.0005);
  CHECK(s[robocal::paramIndexByName("L6.z")] == 0.2);
}
