#include <robocal/kinematics/gravity.hpp>
#include <robocal/robot/puma560.hpp>

namespace robocal {

std::array<DHRow, kJointCount> puma560DH() {
  return {{{0, 0, 90, 0},
           {0, 431.8, 0, 0},
           {149.09, 20.32, -90, 0},
           {433.07, 0, 90, 0},
           {0, 0, -90, 0},
           {0, 0, 0, 0}}};
}

std::array<DHRow, kJointCount> puma560CorkeDH() {
  return {{{0, 0, 90, 0},
           {0, 431.8, 0, 0},
           {150.05, 20.3, -90, 0},
           {431.8, 0, 90, 0},
           {0, 0, -90, 0},
           {0, 0, 0, 0}}};
}

Model puma560NominalModel() {
  // The global frame is the chuck fixture's: x away from the robot, z up. The joint-1 frame
  // (at shoulder height, as in the DH table) sits 550 mm behind it and 400 mm above it.
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.translation() << -550.0, 0.0, 400.0;
  Eigen::Isometry3d flange = Eigen::Isometry3d::Identity();
  flange.translation() << 0.0, 0.0, 56.25;

  Model m = modelFromStandardDH(puma560DH(), base, flange);
  m.name = "PUMA 560 nominal (Lloyd DH), robocal reference cell";
  const std::array<std::pair<double, double>, kJointCount> limits = {
      {{-160, 160}, {-45, 225}, {-225, 45}, {-110, 170}, {-100, 100}, {-266, 266}}};
  for (int j = 0; j < kJointCount; ++j) {
    m.joints[j].min_deg = limits[j].first;
    m.joints[j].max_deg = limits[j].second;
  }
  // Tool fixture: three balls on a triangle of 60 mm radius, 90 to 110 mm past the flange, none
  // on joint 6's axis. Chuck fixture: an equilateral triangle of 150 mm sides on the table.
  m.balls_mm = {Eigen::Vector3d(60.0, 0.0, 90.0), Eigen::Vector3d(-30.0, 51.96, 100.0),
                Eigen::Vector3d(-30.0, -51.96, 110.0)};
  m.chucks_mm = {Eigen::Vector3d(-43.3, -75.0, 0.0), Eigen::Vector3d(-43.3, 75.0, 0.0),
                 Eigen::Vector3d(86.6, 0.0, 0.0)};
  // What gravity pulls on (the fixture: 1 kg, 60 mm past the flange), with no compliance: a rigid
  // arm until a fit identifies it (robocal solve --compliance).
  m.compliance = JointCompliance{puma560GravityLoad(1.0, Eigen::Vector3d(0, 0, 60)), {}};
  return m;
}

GravityLoad puma560GravityLoad(double payload_kg, const Eigen::Vector3d& payload_com_mm) {
  GravityLoad g;
  // Link 1 turns about the vertical: no gravity torque. Centres in m there, mm here.
  g.link_mass_kg = {0.0, 17.4, 4.8, 0.82, 0.34, 0.09};
  g.link_com_mm = {Eigen::Vector3d(0, 0, 0),          Eigen::Vector3d(-363.8, 6, 227.5),
                   Eigen::Vector3d(-20.3, -14.1, 70), Eigen::Vector3d(0, 19, 0),
                   Eigen::Vector3d(0, 0, 0),          Eigen::Vector3d(0, 0, 32)};
  g.payload_kg = payload_kg;
  g.payload_com_mm = payload_com_mm;
  return g;
}

}  // namespace robocal
