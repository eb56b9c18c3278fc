#include <catch2/catch.hpp>

#include <robocal/planner/cell_json.hpp>
#include <robocal/sim/measurements.hpp>

#include <nlohmann/json.hpp>

#include <string>

using namespace robocal;

namespace {

std::string errorOf(const std::string& text) {
  try {
    parseCell(text, "cell.json");
  } catch (const FormatError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("the shipped cell file reads and has the documented defaults") {
  const CellConfig c = loadCellFile(std::string(ROBOCAL_SOURCE_DIR) + "/config/cell.json");
  CHECK(c.bar.nominal_length_mm == kDefaultBarMm);  // the bar robocal simulate assumes
  CHECK(c.bar.extension_lengths_mm == std::vector<double>{0, 150});
  CHECK(c.bar.max_deflection_mm == 2.0);
  CHECK(c.connections.size() == 9);
  CHECK(gridLatitudes(c.grid).size() == 8);
  CHECK(gridLongitudes(c.grid).size() == 12);
  CHECK(c.motion.via_tolerance_mm == 0.5);
  CHECK(c.motion.settle_s == 2.0);
  // Written back and read again: the same settings.
  const CellConfig back = parseCell(cellToJson(c).dump(), "back");
  CHECK(cellToJson(back) == cellToJson(c));
}

TEST_CASE("an empty cell file gives the defaults") {
  const CellConfig c = parseCell("{}");
  CHECK(c.connections.size() == 9);
  CHECK(c.arm_configuration == "auto");
}

TEST_CASE("bad cell files give an error naming the key") {
  CHECK(errorOf(R"({"bar": {"nominal_length_mm": "long"}})").find("bar.nominal_length_mm") !=
        std::string::npos);
  CHECK(errorOf(R"({"bar": {"nominal_length": 100}})").find("bar.nominal_length: unknown key") !=
        std::string::npos);
  CHECK(errorOf(R"({"motion": {"via_tolerance_mm": 2.5}})").find("motion.via_tolerance_mm") !=
        std::string::npos);
  CHECK(errorOf(R"({"grid": {"latitude_first_deg": 50, "latitude_last_deg": 40}})")
            .find("grid.latitude_last_deg") != std::string::npos);
  CHECK(errorOf(R"({"connections": ["B1C1", "B4C1"]})").find("connections[1]") !=
        std::string::npos);
  CHECK(errorOf(R"({"connections": ["B1C1", "B1C1"]})").find("twice") != std::string::npos);
  CHECK(errorOf(R"({"arm_configuration": "sideways"})").find("arm_configuration") !=
        std::string::npos);
  // The refusal names the configurations there are.
  CHECK(errorOf(R"({"arm_configuration": "sideways"})").find("right-up-noflip, right-up-flip") !=
        std::string::npos);
  CHECK(errorOf(R"({"margins": {"wrist_singularity_deg": -1}})")
            .find("margins.wrist_singularity_deg") != std::string::npos);
  CHECK(errorOf(R"({"motion": {"sample_step_mm": 5}})").find("motion.sample_step_mm") !=
        std::string::npos);
  CHECK(errorOf(R"({"grid": {"latitude_last_deg": 90}})").find("grid.latitude_last_deg") !=
        std::string::npos);
  CHECK(errorOf("{not json").find("not valid JSON") != std::string::npos);
  // Found with fuzz_cell: the message dumped a deeply nested value and overflowed the stack.
  const std::string deep = std::string(200000, '[') + std::string(200000, ']');
  CHECK(errorOf(R"({"model_uncertainty": {"models": )" + deep + "}}")
            .find("model_uncertainty.models: expected a whole number, got array") !=
        std::string::npos);
  CHECK(errorOf(R"({"model_uncertainty": {"models": 2.5}})").find("got 2.5") != std::string::npos);
  // Found by fuzz_cell: a number too large for a double escaped as json::out_of_range.
  CHECK(errorOf(R"({"bar": {"nominal_length_mm": 1e30830}})").find("not valid JSON") !=
        std::string::npos);
  CHECK(errorOf("[]").find("top level") != std::string::npos);
}
