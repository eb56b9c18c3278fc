// robocal import --urdf: the command around urdfToModel (tests/formats/test_urdf_import.cpp
// checks the kinematics): what it writes, what it prints, and what it refuses.
#include <catch2/catch.hpp>

#include "cli_helpers.hpp"

#include <robocal/formats/model_json.hpp>

#include <filesystem>

using namespace robocal;
using namespace robocal::test;
using Catch::Matchers::Contains;

namespace {
const std::string kUr5 = ROBOCAL_SOURCE_DIR "/config/ur5.urdf";
}

TEST_CASE("robocal import --urdf writes a UR5 as a model, the cell's fixtures from --fixtures") {
  TempDir dir;
  // A robot's own URDF has no balls or chucks: refused without --fixtures, nothing written.
  auto r = runRobocal("import --urdf " + kUr5 + " --out " + (dir / "ur5.json"));
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output,
             Contains("has no links ball1..ball3 below the tip and chuck1..chuck3 "
                      "below the base: give the cell's balls and chucks with --fixtures"));
  CHECK_FALSE(std::filesystem::exists(dir / "ur5.json"));

  r = runRobocal("import --urdf " + kUr5 + " --out " + (dir / "ur5.json") + " --fixtures " +
                 kModel + " --tip tool0 --name \"UR5 nominal\"");
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.output, Contains("wrote " + (dir / "ur5.json") +
                                ": \"UR5 nominal\", six joints from link world to link tool0"));
  CHECK_THAT(r.output, Contains("  joint elbow_joint           -180.000 ..  180.000 deg\n"));
  CHECK_THAT(r.output, Contains("fixed joints merged into the links: world_joint "
                                "wrist_3_link-tool0_fixed_joint"));
  CHECK_THAT(r.output, Contains("balls and chucks from " + kModel));
  const Model m = loadModelFile(dir / "ur5.json");
  const Model puma = loadModelFile(kModel);
  CHECK(m.name == "UR5 nominal");
  CHECK(m.joints[1].name == "shoulder_lift_joint");
  CHECK(m.balls_mm == puma.balls_mm);
  CHECK(m.chucks_mm == puma.chucks_mm);
}

TEST_CASE("robocal import --urdf reads robocal's own export back, fixtures included") {
  TempDir dir;
  REQUIRE(runRobocal("export --urdf --model " + kModel + " --out " + (dir / "puma.urdf") +
                     " --velocity-deg-per-s 90 --effort-nm 100")
              .exit_code == 0);
  const auto r = runRobocal("import --urdf " + (dir / "puma.urdf") + " --out " + (dir / "m.json"));
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.output, Contains("from link chuck_fixture to link ball_fixture"));
  CHECK_THAT(r.output, Contains("balls and chucks from the URDF's ball and chuck links"));
  const Model puma = loadModelFile(kModel), back = loadModelFile(dir / "m.json");
  for (int b = 0; b < kBallCount; ++b) CHECK((back.balls_mm[b] - puma.balls_mm[b]).norm() < 1e-9);
}

TEST_CASE("robocal import: usage errors and unsuitable files are named") {
  TempDir dir;
  auto r = runRobocal("import --out " + (dir / "m.json"));
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("--urdf"));
  r = runRobocal("import --urdf " + (dir / "none.urdf") + " --out " + (dir / "m.json"));
  CHECK(r.exit_code == 1);
  CHECK_THAT(r.output, Contains("none.urdf"));
  r = runRobocal("import --urdf " + kUr5 + " --out " + (dir / "m.json") + " --fixtures " + kModel +
                 " --tip no_such_link");
  CHECK(r.exit_code == 1);
  CHECK_THAT(r.output, Contains("ur5.urdf: no link named 'no_such_link' (--tip)"));
  r = runRobocal("import --urdf " + kUr5 + " --out " + kUr5 + " --fixtures " + kModel);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("is the URDF file itself"));
  CHECK_FALSE(std::filesystem::exists(dir / "m.json"));
}
