// The PUMA 560's published standard DH tables and the nominal model robocal ships
// (config/puma560.json is this model; a test keeps the two equal).
#pragma once

#include <robocal/kinematics/gravity.hpp>
#include <robocal/kinematics/model.hpp>

namespace robocal {

// Lloyd's values (robotics FAQ): a2 = 431.8, a3 = 20.32, d3 = 149.09, d4 = 433.07 mm.
std::array<DHRow, kJointCount> puma560DH();
// Corke's Robotics Toolbox mdl_puma560: a2 = 431.8, a3 = 20.3, d3 = 150.05, d4 = 431.8 mm.
std::array<DHRow, kJointCount> puma560CorkeDH();

// The PUMA 560's link masses and centres (Armstrong, Khatib and Burdick, ICRA 1986, as Corke's
// mdl_puma560 tabulates them), with a payload of `payload_kg` at `payload_com_mm`.
GravityLoad puma560GravityLoad(double payload_kg, const Eigen::Vector3d& payload_com_mm);

// The nominal PUMA 560 of a robocal cell: Lloyd's DH table, the joint-1 frame at shoulder height
// placed relative to the chuck fixture, the flange 56.25 mm past the wrist centre, the three
// balls on a tool fixture and the three chucks on the table fixture, Corke's joint limits, and the
// links' and the fixture's weights with no compliance (a rigid arm: see gravity.hpp).
Model puma560NominalModel();

}  // namespace robocal
