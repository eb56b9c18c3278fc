// The operator's steps between shells (planner/swaps.hpp): walks to another chuck, ball and
// extension changes, and the shipped cells' connection order that keeps the walks few.
#include <catch2/catch.hpp>

#include <robocal/formats/model_json.hpp>
#include <robocal/planner/cell_json.hpp>
#include <robocal/planner/swaps.hpp>

#include <string>

using namespace robocal;

namespace {

// Shells in running order, as planCell makes them: each extension in turn, the cell's connections
// in their listed order.
Plan shellsOf(const std::vector<Connection>& connections, const std::vector<double>& extensions) {
  Plan plan;
  for (double extension : extensions)
    for (const Connection& c : connections) {
      ShellPlan shell;
      shell.connection = c;
      shell.extension_mm = extension;
      plan.shells.push_back(shell);
    }
  return plan;
}

}  // namespace

TEST_CASE("the operator's steps count walks to another chuck and their distance",
          "[planner][swaps]") {
  const Model model = loadModelFile(ROBOCAL_SOURCE_DIR "/config/puma560-paper.json");
  // B1C1 -> B2C1 (ball) -> B2C3 (walk) -> B2C3 longer bar (extension) -> B1C2 (walk and ball).
  Plan plan = shellsOf(parseConnections("B1C1,B2C1,B2C3"), {0.0});
  plan.shells.push_back(plan.shells.back());
  plan.shells.back().extension_mm = 150;
  plan.shells.push_back(shellsOf(parseConnections("B1C2"), {150.0}).shells[0]);
  const OperatorSteps steps = operatorSteps(model, plan);
  CHECK(steps.connects == 5);
  CHECK(steps.chuck_changes == 2);
  CHECK(steps.ball_changes == 2);
  CHECK(steps.extension_changes == 1);
  const double c1c3 = (model.chucks_mm[0] - model.chucks_mm[2]).norm();
  const double c3c2 = (model.chucks_mm[2] - model.chucks_mm[1]).norm();
  CHECK(steps.walk_mm == Approx(c1c3 + c3c2));
  CHECK(describeOperatorSteps(steps) ==
        "5 connects: 2 walks to another chuck (0.3 m), 2 ball changes, 1 extension change");
  // One shell: nothing changes.
  plan.shells.resize(1);
  CHECK(describeOperatorSteps(operatorSteps(model, plan)) ==
        "1 connect: 0 walks to another chuck (0.0 m), 0 ball changes, 0 extension changes");
}

TEST_CASE("the shipped cells order their connections for two walks an extension",
          "[planner][swaps]") {
  for (const auto& [cell_file, model_file] :
       {std::pair{"/config/cell.json", "/config/puma560-paper.json"},
        std::pair{"/config/cell-rx160.json", "/config/rx160.json"}}) {
    INFO(cell_file);
    const CellConfig cell = loadCellFile(std::string(ROBOCAL_SOURCE_DIR) + cell_file);
    const Model model = loadModelFile(std::string(ROBOCAL_SOURCE_DIR) + model_file);
    const Plan plan = planCell(model, cell);  // the order the daemon runs
    REQUIRE(plan.shells.size() == 9 * cell.bar.extension_lengths_mm.size());
    const OperatorSteps steps = operatorSteps(model, plan);
    // Each chuck's three balls together: two walks an extension and one between them.
    const int extensions = static_cast<int>(cell.bar.extension_lengths_mm.size());
    CHECK(steps.chuck_changes == 3 * extensions - 1);
    // The ball-major order of "all" walks at every shell.
    const OperatorSteps ball_major =
        operatorSteps(model, shellsOf(allConnections(), cell.bar.extension_lengths_mm));
    CHECK(ball_major.chuck_changes == 9 * extensions - 1);
    CHECK(steps.walk_mm < ball_major.walk_mm / 3);
  }
}
