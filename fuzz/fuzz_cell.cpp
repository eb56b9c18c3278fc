// The cell file (config/cell.json, docs/cell-format.md). parseCell returns a validated
// CellConfig or throws FormatError. Property: the cell written back (cellToJson) parses to the
// same settings, exactly.
#include "fuzz_common.hpp"

#include <robocal/planner/cell_json.hpp>

using namespace robocal;
using robocal::fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return robocal::fuzz::guarded(data, size, [](const std::string& text) {
    CellConfig cell;
    try {
      cell = parseCell(text, "fuzz.json");
    } catch (const FormatError&) {
      return;
    }
    const nlohmann::ordered_json written = cellToJson(cell);
    CellConfig again;
    try {
      again = parseCell(written.dump(2), "written");
    } catch (const FormatError& e) {
      robocal::fuzz::fail("written cell does not parse", e.what());
    }
    std::string path = "cell";
    check(robocal::fuzz::sameJson(written, cellToJson(again), 0, 0, path),
          "cell changed on a round trip", path);
  });
}
