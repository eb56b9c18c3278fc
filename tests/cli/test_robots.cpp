// Another arm than the PUMA through the whole offline job, as a user runs it: a UR5 imported
// from its URDF (no spherical wrist: only the numeric inverse kinematics serves it), stood on
// the table, planned, simulated, solved and judged against its truth (docs/robots.md).
#include <catch2/catch.hpp>

#include "cli_helpers.hpp"

#include <fstream>
#include <nlohmann/json.hpp>

using namespace robocal::test;
using json = nlohmann::json;

TEST_CASE("a UR5 from its URDF: plan, simulate, solve and compensate offline", "[cli][robots]") {
  TempDir dir;
  const std::string src = ROBOCAL_SOURCE_DIR;
  REQUIRE(runRobocal("import --urdf " + src + "/config/ur5.urdf --fixtures " + src +
                     "/config/puma560-paper.json --out " + (dir / "ur5.json"))
              .exit_code == 0);
  // The URDF's world_joint hangs the arm 800 mm above the chucks: stand it on the table 450 mm
  // behind them, its shoulder level with the chuck fixture.
  json model = json::parse(std::ifstream(dir / "ur5.json"));
  model["links"][0].update({{"x", -450.0}, {"y", 0.0}, {"z", -10.841}, {"rz", 0.0}});
  std::ofstream(dir / "ur5-cell.json") << model.dump(2);
  // Three connections: rank 36 with a third of the main job's shells.
  json cell = json::parse(std::ifstream(src + "/config/cell.json"));
  cell["connections"] = {"B1C1", "B2C2", "B3C3"};
  std::ofstream(dir / "cell.json") << cell.dump(2);

  const RunResult plan = runRobocal("plan --quiet --model " + (dir / "ur5-cell.json") + " --cell " +
                                    (dir / "cell.json") + " --out " + (dir / "plan.json"));
  INFO(plan.output);
  REQUIRE(plan.exit_code == 0);
  CHECK_THAT(plan.output, Catch::Contains("identification: rank 36 of 36"));
  REQUIRE(runRobocal("simulate --model " + (dir / "ur5-cell.json") + " --plan " +
                     (dir / "plan.json") + " --seed 7 --out " + (dir / "samples.csv") +
                     " --truth-out " + (dir / "truth.json"))
              .exit_code == 0);
  const RunResult solve = runRobocal("solve --model " + (dir / "ur5-cell.json") + " " +
                                     (dir / "samples.csv") + " --out " + (dir / "cal.json"));
  INFO(solve.output);
  REQUIRE(solve.exit_code == 0);
  CHECK_THAT(solve.output, Catch::Contains("usable as a calibration (rank 36 of 36)"));
  const RunResult accuracy =
      runRobocal("accuracy --json --calibrated " + (dir / "cal.json") + " --truth " +
                     (dir / "truth.json") + " --cell " + (dir / "cell.json"),
                 false);
  INFO(accuracy.output);
  REQUIRE(accuracy.exit_code == 0);
  const json a = json::parse(accuracy.output);
  const double nominal_mm = a["nominal_commanded_position_error_mm"]["rms"];
  const double compensated_mm = a["compensated_commanded_position_error_mm"]["rms"];
  CHECK(a["solved"].get<int>() == a["poses"].get<int>());  // every target compensated
  CHECK(nominal_mm > 10 * compensated_mm);                 // the acceptance: 10x better
}
