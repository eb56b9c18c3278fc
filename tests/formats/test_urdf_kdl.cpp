// URDF checked by readers other than robocal's: Orocos KDL builds the chain from the file
// (kdl_fk.py: Python's XML reader and Debian's python3-pykdl, nothing of urdfdom or robocal) and
// its forward kinematics must be robocal's to 1 um at 1,000 joint vectors; urdfdom's check_urdf
// (liburdfdom-tools) accepts the file. Both are installed by scripts/setup.sh: a machine without
// them fails these tests, saying what to install.
#include <catch2/catch.hpp>

#include <robocal/formats/error.hpp>
#include <robocal/formats/urdf.hpp>
#include <robocal/formats/urdf_import.hpp>
#include <robocal/kinematics/units.hpp>

#include "../cli/cli_helpers.hpp"
#include "urdf_fk.hpp"

#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace robocal;
using namespace robocal::test;

namespace {

// The acceptance figure: 1 um.
constexpr double kKdlTolMm = 1e-3;
constexpr double kKdlTolRad = 1e-9;

// Debian's python, where python3-pykdl installs (a python3 earlier in PATH may be another one).
std::string python() {
  return std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
}

// KDL's pose of `tip` in `base`'s frame at each joint vector (radians, chain order): positions in
// mm.
std::vector<Eigen::Isometry3d> kdlPoses(const std::string& urdf_path, const std::string& base,
                                        const std::string& tip,
                                        const std::vector<std::vector<double>>& joints) {
  const TempDir dir;
  const std::string csv = dir / "joints.csv";
  {
    std::ofstream out(csv);
    out.precision(17);
    for (const auto& q : joints) {
      for (size_t i = 0; i < q.size(); ++i) out << (i ? "," : "") << q[i];
      out << "\n";
    }
  }
  // stdout holds the poses alone; what the script says goes to its own file.
  const std::string errors_path = dir / "stderr.txt";
  const RunResult r =
      runCommand(python() + " " ROBOCAL_SOURCE_DIR "/tests/formats/kdl_fk.py " + urdf_path + " " +
                 base + " " + tip + " " + csv + " 2>" + errors_path);
  const std::string errors = readTextFile(errors_path);
  INFO(errors.substr(0, 2000));
  if (errors.find("No module named 'PyKDL'") != std::string::npos)
    FAIL("Orocos KDL's Python module is missing: install python3-pykdl (scripts/setup.sh)");
  REQUIRE(r.exit_code == 0);
  std::vector<Eigen::Isometry3d> poses;
  std::istringstream in(r.output);
  for (std::string line; std::getline(in, line);) {
    std::istringstream row(line);
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    for (int i = 0; i < 3; ++i) row >> pose.translation()[i];
    for (int i = 0; i < 9; ++i) row >> pose.linear()(i / 3, i % 3);
    REQUIRE(row);
    pose.translation() *= 1000.0;
    poses.push_back(pose);
  }
  REQUIRE(poses.size() == joints.size());
  return poses;
}

void checkUrdf(const std::string& path) {
  const RunResult r = runCommand("check_urdf " + path + " 2>&1");
  INFO(r.output);
  if (r.exit_code == 127)
    FAIL("check_urdf is missing: install liburdfdom-tools (scripts/setup.sh)");
  CHECK(r.exit_code == 0);
  CHECK_THAT(r.output, Catch::Contains("Successfully Parsed XML"));
}

struct Worst {
  double mm = 0, rad = 0;
};

// KDL's forward kinematics of the file against `m`'s, at joint vectors drawn from rng; the joint
// values given to KDL are the readings in radians times the gains.
Worst compareWithKdl(const Model& m, const std::string& urdf_path, const std::string& base,
                     const std::string& tip, int count, std::mt19937_64& rng) {
  std::vector<JointsDeg> readings;
  std::vector<std::vector<double>> values;
  for (int n = 0; n < count; ++n) {
    readings.push_back(randomReadings(m, rng));
    std::vector<double> v;
    for (int j = 0; j < kJointCount; ++j) v.push_back(m.joints[j].gain * degToRad(readings[n][j]));
    values.push_back(v);
  }
  const auto poses = kdlPoses(urdf_path, base, tip, values);
  const Kinematics kin(m);
  Worst w;
  for (int n = 0; n < count; ++n) {
    const Eigen::Isometry3d ours = kin.toolPose(readings[n]);
    w.mm = std::max(w.mm, (ours.translation() - poses[n].translation()).norm());
    w.rad = std::max(w.rad, angleBetween(ours.linear(), poses[n].linear()));
  }
  return w;
}

}  // namespace

TEST_CASE("KDL reads robocal's URDF export as robocal computes it: 1,000 joint vectors, 1 um",
          "[kdl]") {
  const TempDir dir;
  std::mt19937_64 rng(31);
  Worst worst;
  for (int model = 0; model < 5; ++model) {
    Model m = calibratedLike(rng);
    m.joints[2].gain = 1.0007;  // the joint value KDL gets is reading * gain
    const std::string path = dir / ("m" + std::to_string(model) + ".urdf");
    writeTextFileAtomic(path, modelToUrdf(m));
    if (model == 0) checkUrdf(path);
    const Worst w = compareWithKdl(m, path, kUrdfBaseLink, kUrdfBallFixtureLink, 200, rng);
    worst.mm = std::max(worst.mm, w.mm);
    worst.rad = std::max(worst.rad, w.rad);
  }
  CAPTURE(worst.mm, worst.rad);
  CHECK(worst.mm <= kKdlTolMm);
  CHECK(worst.rad <= kKdlTolRad);
}

TEST_CASE("KDL reads a UR5's URDF as robocal's import of it computes it", "[kdl]") {
  const std::string path = ROBOCAL_SOURCE_DIR "/config/ur5.urdf";
  checkUrdf(path);
  UrdfImportOptions options;
  options.tip_link = "tool0";
  const Model m = urdfToModel(readTextFile(path), path, options).model;
  std::mt19937_64 rng(32);
  const Worst w = compareWithKdl(m, path, "world", "tool0", 1000, rng);
  CAPTURE(w.mm, w.rad);
  CHECK(w.mm <= kKdlTolMm);
  CHECK(w.rad <= kKdlTolRad);
}
