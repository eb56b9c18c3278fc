#include <robocal/formats/urdf_import.hpp>

#include <robocal/formats/urdf.hpp>
#include <robocal/kinematics/units.hpp>

#include <urdf_parser/urdf_parser.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>

namespace robocal {
namespace {

constexpr double kMmPerM = 1000.0;
constexpr double kContinuousLimitDeg = 360.0;

Eigen::Isometry3d toIsometryMm(const urdf::Pose& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() << pose.position.x * kMmPerM, pose.position.y * kMmPerM,
      pose.position.z * kMmPerM;
  t.linear() =
      Eigen::Quaterniond(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z)
          .normalized()
          .toRotationMatrix();
  return t;
}

bool movable(const urdf::Joint& j) {
  return j.type == urdf::Joint::REVOLUTE || j.type == urdf::Joint::CONTINUOUS;
}

const char* typeName(int type) {
  switch (type) {
    case urdf::Joint::REVOLUTE:
      return "revolute";
    case urdf::Joint::CONTINUOUS:
      return "continuous";
    case urdf::Joint::PRISMATIC:
      return "prismatic";
    case urdf::Joint::FLOATING:
      return "floating";
    case urdf::Joint::PLANAR:
      return "planar";
    case urdf::Joint::FIXED:
      return "fixed";
    default:
      return "unknown";
  }
}

// A rotation that takes z onto `axis` (unit): R(axis, q) = A Rz(q) A^-1.
Eigen::Matrix3d alignZ(const Eigen::Vector3d& axis) {
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  if ((axis - z).norm() < 1e-12) return Eigen::Matrix3d::Identity();
  if ((axis + z).norm() < 1e-12) return Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).matrix();
  return Eigen::Quaterniond::FromTwoVectors(z, axis).toRotationMatrix();
}

// The pose of `link` in `from`'s frame when only fixed joints lie between them (`from` above).
std::optional<Eigen::Isometry3d> fixedBelow(const urdf::ModelInterface& urdf,
                                            const std::string& from, const std::string& link) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  urdf::LinkConstSharedPtr at = urdf.getLink(link);
  for (std::size_t steps = 0; at && at->name != from; ++steps) {
    const urdf::JointSharedPtr& j = at->parent_joint;
    if (!j || j->type != urdf::Joint::FIXED || steps > urdf.links_.size()) return std::nullopt;
    pose = toIsometryMm(j->parent_to_joint_origin_transform) * pose;
    at = urdf.getLink(j->parent_link_name);
  }
  if (!at) return std::nullopt;
  return pose;
}

}  // namespace

UrdfImport urdfToModel(const std::string& urdf_text, const std::string& source,
                       const UrdfImportOptions& options) {
  const auto fail = [&](const std::string& what) {
    throw std::invalid_argument(source + ": " + what);
  };
  const urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDF(urdf_text);
  if (!urdf) fail("not a URDF that urdfdom can read (its reasons are printed above)");
  // urdfdom's links hold their children by shared_ptr: a loop of links in a file (refused below,
  // or off the chain and never seen) would never be freed. Cut them when done, however this
  // function ends. (A loop through the root urdfdom refuses itself, and does not free.)
  struct CutLinksAtExit {
    const urdf::ModelInterface& model;
    ~CutLinksAtExit() {
      for (const auto& entry : model.links_) {
        entry.second->child_links.clear();
        entry.second->child_joints.clear();
      }
    }
  } cut_links_at_exit{*urdf};
  // urdfdom keeps one parent per link and drops a second joint into it without a word: a link
  // below two joints closes a loop, which no serial chain has.
  std::map<std::string, std::string> parent_joint_of;
  for (const auto& [name, joint] : urdf->joints_) {
    const auto [first, inserted] = parent_joint_of.emplace(joint->child_link_name, name);
    if (!inserted)
      fail("link '" + joint->child_link_name + "' is the child of two joints ('" + first->second +
           "' and '" + name + "'): the links form a loop, a URDF must be a tree");
  }

  UrdfImport out;
  out.base_link = options.base_link;
  if (out.base_link.empty())
    out.base_link = urdf->getLink(kUrdfBaseLink) ? kUrdfBaseLink : urdf->getRoot()->name;
  if (!urdf->getLink(out.base_link)) fail("no link named '" + out.base_link + "' (--base)");

  out.tip_link = options.tip_link;
  if (out.tip_link.empty() && urdf->getLink(kUrdfBallFixtureLink))
    out.tip_link = kUrdfBallFixtureLink;
  if (out.tip_link.empty()) {
    // Down from the base to the sixth joint that is not fixed, along the only branch that has
    // one (a prismatic joint counts here, to be refused by name below).
    urdf::LinkConstSharedPtr at = urdf->getLink(out.base_link);
    int seen = 0;
    // A loop of links (which urdfdom does not refuse when the root is outside it) ends the search
    // after as many steps as there are links.
    const std::size_t most_steps = urdf->links_.size();
    const std::function<bool(const urdf::Link&, std::size_t)> leadsToMovable =
        [&](const urdf::Link& l, std::size_t depth) {
          if (depth > most_steps) fail("the links below '" + l.name + "' form a loop");
          for (const urdf::JointSharedPtr& j : l.child_joints)
            if (j->type != urdf::Joint::FIXED ||
                leadsToMovable(*urdf->getLink(j->child_link_name), depth + 1))
              return true;
          return false;
        };
    std::size_t steps = 0;
    while (seen < kJointCount) {
      if (++steps > most_steps) fail("the links below '" + out.base_link + "' form a loop");
      urdf::JointSharedPtr next;
      for (const urdf::JointSharedPtr& j : at->child_joints) {
        if (j->type == urdf::Joint::FIXED && !leadsToMovable(*urdf->getLink(j->child_link_name), 0))
          continue;
        if (next)
          fail("the chain branches at link '" + at->name + "' (joints '" + next->name + "' and '" +
               j->name + "'): say where it ends with --tip LINK");
        next = j;
      }
      if (!next)
        fail("only " + std::to_string(seen) + " movable joints below link '" + out.base_link +
             "'; a robocal model has six");
      seen += next->type != urdf::Joint::FIXED;
      at = urdf->getLink(next->child_link_name);
    }
    out.tip_link = at->name;
  }
  if (!urdf->getLink(out.tip_link)) fail("no link named '" + out.tip_link + "' (--tip)");

  // The joints from the base down to the tip.
  std::vector<urdf::JointSharedPtr> chain;
  for (urdf::LinkConstSharedPtr at = urdf->getLink(out.tip_link); at->name != out.base_link;) {
    if (!at->parent_joint || chain.size() > urdf->links_.size())
      fail("link '" + out.base_link + "' is not above link '" + out.tip_link + "'");
    chain.push_back(at->parent_joint);
    at = urdf->getLink(at->parent_joint->parent_link_name);
  }
  std::reverse(chain.begin(), chain.end());

  Model& m = out.model;
  m.name = options.name.empty() ? urdf->getName() + " (URDF)" : options.name;
  int k = 0;  // movable joints so far
  Eigen::Isometry3d pending = Eigen::Isometry3d::Identity();
  std::string link_name = out.base_link;
  for (const urdf::JointSharedPtr& j : chain) {
    if (j->mimic) fail("joint '" + j->name + "' mimics another: robocal's joints are independent");
    if (j->type == urdf::Joint::FIXED) {
      pending = pending * toIsometryMm(j->parent_to_joint_origin_transform);
      out.fixed_joints.push_back(j->name);
      continue;
    }
    if (!movable(*j))
      fail("joint '" + j->name + "' is " + typeName(j->type) +
           ": robocal models six revolute joints");
    if (k == kJointCount)
      fail("more than six movable joints from '" + out.base_link + "' to '" + out.tip_link +
           "' (the seventh: '" + j->name + "')");
    const Eigen::Vector3d axis(j->axis.x, j->axis.y, j->axis.z);
    if (!(axis.norm() > 0) || !axis.allFinite()) fail("joint '" + j->name + "' has no axis");
    Eigen::Isometry3d align = Eigen::Isometry3d::Identity();
    align.linear() = alignZ(axis.normalized());
    const Eigen::Isometry3d before = pending * toIsometryMm(j->parent_to_joint_origin_transform);
    // Any turn about the joint's own z keeps the kinematics (the next link starts with its
    // inverse); the one that zeroes the link's ry keeps its ZYX angles away from ry = +-90 deg,
    // where rz and rx turn about the same axis and a fit cannot tell them apart (a UR's shoulder,
    // axes along y, came in at ry = 90 deg and left the fit one parameter short).
    const Eigen::Matrix3d r = before.linear() * align.linear();
    double phi = std::atan2(-r(2, 0), r(2, 1));
    if (phi > M_PI / 2) phi -= M_PI;  // of the two turns that do it, the smaller
    if (phi <= -M_PI / 2) phi += M_PI;
    align.linear() = align.linear() * Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitZ()).matrix();
    pending = before * align;
    m.links[k] = linkFromTransform(pending, link_name);
    JointParams& joint = m.joints[k];
    joint.name = j->name;
    if (j->type == urdf::Joint::CONTINUOUS) {
      joint.min_deg = -kContinuousLimitDeg;
      joint.max_deg = kContinuousLimitDeg;
    } else {
      if (!j->limits) fail("revolute joint '" + j->name + "' has no <limit>");
      joint.min_deg = j->limits->lower * kDegPerRad;
      joint.max_deg = j->limits->upper * kDegPerRad;
      if (!std::isfinite(joint.min_deg) || !std::isfinite(joint.max_deg) ||
          !(joint.min_deg < joint.max_deg))
        fail("joint '" + j->name + "': expected finite limits, the lower below the upper");
    }
    if (j->limits) {  // rated speed and torque, for an export to carry on (0: not given)
      joint.velocity_deg_per_s = std::max(0.0, j->limits->velocity) * kDegPerRad;
      joint.effort_nm = std::max(0.0, j->limits->effort);
      // The model file's own bounds (model_json.cpp), so that what is written reads back.
      if (!(joint.velocity_deg_per_s <= kMaxVelocityDegPerS))
        fail("joint '" + j->name + "': velocity past " +
             std::to_string(kMaxVelocityDegPerS / kDegPerRad) + " rad/s");
      if (!(joint.effort_nm <= kMaxEffortNm))
        fail("joint '" + j->name + "': effort past " + std::to_string(kMaxEffortNm) + " N m");
    }
    pending = align.inverse();
    link_name = j->child_link_name;
    ++k;
  }
  if (k < kJointCount)
    fail(std::to_string(k) + " movable joints from '" + out.base_link + "' to '" + out.tip_link +
         "'; a robocal model has six");
  m.links[kJointCount] = linkFromTransform(pending, out.tip_link);

  // The fixtures, when the file has them where robocal's export puts them.
  bool found = true;
  for (int b = 0; b < kBallCount; ++b) {
    const auto pose = fixedBelow(*urdf, out.tip_link, "ball" + std::to_string(b + 1));
    found = found && pose;
    m.balls_mm[b] = pose ? Eigen::Vector3d(pose->translation()) : Eigen::Vector3d::Zero();
  }
  for (int c = 0; c < kChuckCount; ++c) {
    const auto pose = fixedBelow(*urdf, out.base_link, "chuck" + std::to_string(c + 1));
    found = found && pose;
    m.chucks_mm[c] = pose ? Eigen::Vector3d(pose->translation()) : Eigen::Vector3d::Zero();
  }
  out.fixtures_found = found;
  return out;
}

}  // namespace robocal
