#include <catch2/catch.hpp>

#include "cli_helpers.hpp"

#include <robocal/formats/model_json.hpp>
#include <robocal/formats/urdf.hpp>

#include <filesystem>
#include <nlohmann/json.hpp>

using namespace robocal;
using namespace robocal::test;
using Catch::Matchers::Contains;

namespace {
// The shipped PUMA states no rated speed or torque: the export is given them.
const std::string kRated = " --velocity-deg-per-s 90 --effort-nm 100";
}  // namespace

TEST_CASE("robocal export --urdf writes the writer's URDF of the model and prints the gains") {
  TempDir dir;
  const auto r =
      runRobocal("export --urdf --model " + kModel + " --out " + (dir / "puma.urdf") + kRated);
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  const Model model = loadModelFile(kModel);
  UrdfOptions options;
  options.robot_name = urdfRobotName(model);
  options.source = std::filesystem::path(kModel).lexically_normal().string();
  options.velocity_deg_per_s = 90;
  options.effort_nm = 100;
  CHECK(readTextFile(dir / "puma.urdf") == modelToUrdf(model, options));
  CHECK_FALSE(std::filesystem::exists(dir / "puma.urdf.tmp"));
  CHECK_THAT(r.output,
             Contains("wrote " + (dir / "puma.urdf") +
                      ": robot \"puma_560_nominal_lloyd_dh_robocal_reference_cell\", revolute "
                      "joints J1..J6 from chuck_fixture to ball_fixture"));
  CHECK_THAT(r.output, Contains("joint gains (URDF cannot hold them; also in the file's comment): "
                                "J1 1 J2 1 J3 1 J4 1 J5 1 J6 1\n"));
  CHECK_THAT(r.output, Contains("every gain is 1: the URDF joint value is the controller's reading "
                                "in radians"));
}

TEST_CASE("robocal export --urdf of a model with gains other than 1 says what the joint value is") {
  TempDir dir;
  Model model = loadModelFile(kModel);
  model.name = "calibrated";
  model.joints[2].gain = 1.000728;
  saveModelFile(dir / "cal.json", model);
  const auto r = runRobocal("export --urdf --model " + (dir / "cal.json") + " --out " +
                            (dir / "cal.urdf") + " --name puma" + kRated);
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.output, Contains("robot \"puma\""));
  CHECK_THAT(r.output, Contains("J2 1 J3 1.000728 J4 1"));
  CHECK_THAT(r.output, Contains("some gains are not 1: for exact forward kinematics the URDF "
                                "joint value must be\nreading * gain (radians), not the reading"));
  const std::string text = readTextFile(dir / "cal.urdf");
  CHECK_THAT(text, Contains("<robot name=\"puma\">"));
  CHECK_THAT(text, Contains("    J3 gain 1.000728   (not 1)\n"));
}

TEST_CASE("robocal export: usage errors and unreadable or unwritable files are named") {
  TempDir dir;
  auto r = runRobocal("export --model " + kModel + " --out " + (dir / "x.urdf"));
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("robocal export: say which format to write: --urdf"));
  r = runRobocal("export --urdf --model " + kModel);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("--out"));
  r = runRobocal("export --urdf --model " + kModel + " --out " + (dir / "x.urdf") + " --name ''");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("--name must not be empty"));
  r = runRobocal("export --urdf --model " + (dir / "missing.json") + " --out " + (dir / "x.urdf"));
  CHECK(r.exit_code == 1);
  CHECK_THAT(r.output, Contains(dir / "missing.json") && Contains("cannot open"));
  r = runRobocal("export --urdf --model " + kModel + " --out " + (dir / "no/such/dir/x.urdf") +
                 kRated);
  CHECK(r.exit_code == 1);
  CHECK_THAT(r.output, Contains(dir / "no/such/dir/x.urdf.tmp") && Contains("cannot create"));
  std::filesystem::copy_file(kModel, dir / "m.json");
  r = runRobocal("export --urdf --model " + (dir / "m.json") + " --out " + (dir / "m.json"));
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("is the model file itself"));
  CHECK(readTextFile(dir / "m.json") == readTextFile(kModel));
  // No rated speed and torque in the model and none given: refused, naming the joints.
  r = runRobocal("export --urdf --model " + kModel + " --out " + (dir / "x.urdf"));
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("URDF needs each joint's rated velocity and effort, and " + kModel +
                                " has none for: J1 velocity, J1 effort"));
  CHECK_THAT(r.output, Contains("Give them with --velocity-deg-per-s and --effort-nm"));
  r = runRobocal("export --urdf --model " + kModel + " --out " + (dir / "x.urdf") +
                 " --velocity-deg-per-s 0 --effort-nm 100");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("--velocity-deg-per-s expects a positive number, not '0'"));
  CHECK_FALSE(std::filesystem::exists(dir / "x.urdf"));
}

TEST_CASE("robocal export --frames and --dh write the frames and the DH table with its error") {
  const TempDir dir;
  auto r = runRobocal("export --dh --model " + kModel + " --out " + (dir / "puma.csv"));
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.output, Catch::Matchers::Contains("joints taken as parallel: 2-3"));
  const std::string table = readTextFile(dir / "puma.csv");
  CHECK_THAT(table, Catch::Matchers::Contains("joint,theta_offset_deg,d_mm,a_mm,alpha_deg,gain"));
  CHECK_THAT(table, Catch::Matchers::Contains("2,0.000000000,0.000000,431.800000,"));  // Lloyd's a2
  r = runRobocal("export --frames --model " + kModel + " --out " + (dir / "puma.json"));
  REQUIRE(r.exit_code == 0);
  const auto frames = nlohmann::json::parse(readTextFile(dir / "puma.json"));
  CHECK(frames["links"].size() == 7);
  CHECK(frames["dh"]["parallel_joints"] == nlohmann::json::parse("[[2, 3]]"));

  // A calibrated model's nearly parallel joints 2 and 3: the table says what it costs, and with
  // no tolerance it is exact.
  r = runRobocal("simulate --model " + kModel +
                 " --seed 3 --connections B1C1 --points-per-shell 1" + " --out " + (dir / "x.csv") +
                 " --truth-out " + (dir / "truth.json"));
  REQUIRE(r.exit_code == 0);
  r = runRobocal("export --dh --model " + (dir / "truth.json") + " --out " + (dir / "t.csv"));
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.output, Catch::Matchers::Contains("the table is not exact"));
  r = runRobocal("export --dh --parallel-tolerance-deg 0 --model " + (dir / "truth.json") +
                 " --out " + (dir / "t.csv"));
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.output, Catch::Matchers::Contains("joints taken as parallel: none"));
  CHECK(r.output.find("the table is not exact") == std::string::npos);

  for (const std::string bad :
       {"--dh --urdf", "--frames --name x", "--dh --parallel-tolerance-deg 95",
        "--urdf --parallel-tolerance-deg 1", ""}) {
    INFO(bad);
    r = runRobocal("export " + bad + " --model " + kModel + " --out " + (dir / "bad.out"), false);
    CHECK(r.exit_code == 2);
    CHECK_FALSE(std::filesystem::exists(dir / "bad.out"));
  }
}
