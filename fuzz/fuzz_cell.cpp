// The cell file (config/cell.json, docs/cell-format.md). parseCell returns a validated
// CellConfig or throws FormatError. Property: the cell written back (cellToJson) parses to the
// same settings, exactly.
#include "fuzz_common.hpp"

#include <robocal/planner/cell_json.hpp>

using namespace robocal;
using robocal::fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return robocal::fuzz::guarded(data, size, [](const std::string& text) {
    const auto both = robocal::fuzz::readWriteRead<FormatError>(
        text, [](const std::string& t) { return parseCell(t, "fuzz.json"); },
        [](const CellConfig& c) { return cellToJson(c).dump(2); }, "written cell does not parse");
    if (!both) return;
    const auto& [cell, again] = *both;
    std::string path = "cell";
    check(robocal::fuzz::sameJson(cellToJson(cell), cellToJson(again), 0, 0, path),
          "cell changed on a round trip", path);
  });
}
