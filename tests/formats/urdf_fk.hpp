// Test helpers for the URDF export and import: a URDF parsed by urdfdom and its forward
// kinematics composed from the parsed joints alone, an independent reader of robocal's files.
#pragma once

#include <catch2/catch.hpp>

#include <robocal/kinematics/kinematics.hpp>
#include <robocal/robot/puma560.hpp>

#include <urdf_parser/urdf_parser.h>

#include <Eigen/Geometry>
#include <functional>
#include <map>
#include <random>
#include <string>

namespace robocal::test {

constexpr double kPositionTolMm = 1e-6;
constexpr double kAngleTolRad = 1e-9;

inline urdf::ModelInterfaceSharedPtr parse(const std::string& text) {
  urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(text);
  REQUIRE(model);
  return model;
}

inline Eigen::Isometry3d toEigen(const urdf::Pose& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() << pose.position.x, pose.position.y, pose.position.z;
  t.linear() =
      Eigen::Quaterniond(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z)
          .normalized()
          .toRotationMatrix();
  return t;
}

// Forward kinematics of a parsed URDF from its joints alone: the pose of every link in the root
// link's frame (meters), with the revolute joints' values (radians) given by joint name.
inline std::map<std::string, Eigen::Isometry3d> linkPoses(
    const urdf::ModelInterface& model, const std::map<std::string, double>& values) {
  std::map<std::string, Eigen::Isometry3d> poses;
  std::function<void(const urdf::Link&, const Eigen::Isometry3d&)> walk =
      [&](const urdf::Link& link, const Eigen::Isometry3d& pose) {
        poses[link.name] = pose;
        for (const urdf::JointSharedPtr& joint : link.child_joints) {
          Eigen::Isometry3d child = pose * toEigen(joint->parent_to_joint_origin_transform);
          if (joint->type == urdf::Joint::REVOLUTE || joint->type == urdf::Joint::CONTINUOUS) {
            const Eigen::Vector3d axis(joint->axis.x, joint->axis.y, joint->axis.z);
            child = child * Eigen::AngleAxisd(values.at(joint->name), axis.normalized());
          } else {
            REQUIRE(joint->type == urdf::Joint::FIXED);
          }
          walk(*model.getLink(joint->child_link_name), child);
        }
      };
  walk(*model.getRoot(), Eigen::Isometry3d::Identity());
  return poses;
}

// A model with every joint's rated speed and torque set (URDF requires them): 90 deg/s, 100 N m.
inline Model rated(Model m) {
  for (JointParams& j : m.joints) {
    j.velocity_deg_per_s = 90.0;
    j.effort_nm = 100.0;
  }
  return m;
}

// A model as a calibration leaves it: every link parameter and joint offset of the nominal PUMA
// moved a little (gains are left at 1), rated.

inline Model calibratedLike(std::mt19937_64& rng) {
  const Model nominal = puma560NominalModel();
  const ParamVector sigma = paramSigmas(2.0, 0.3, 0.5, 0.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  ParamVector p = toParams(nominal);
  for (int i = 0; i < kParamCount; ++i) p[i] += sigma[i] * noise(rng);
  Model m = withParams(nominal, p);
  m.name = "PUMA 560 calibrated-like";
  for (JointParams& j : m.joints) j.gain = 1.0;
  return rated(m);
}

inline JointsDeg randomReadings(const Model& m, std::mt19937_64& rng) {
  JointsDeg q;
  for (int j = 0; j < kJointCount; ++j)
    q[j] = std::uniform_real_distribution<double>(m.joints[j].min_deg, m.joints[j].max_deg)(rng);
  return q;
}

inline double angleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

}  // namespace robocal::test
