// The cell file (docs/cell-format.md): JSON, every key optional (defaults as in CellConfig),
// unknown keys are errors. Errors are FormatError naming the file and the key.
#pragma once

#include <robocal/formats/error.hpp>
#include <robocal/planner/cell.hpp>

#include <nlohmann/json_fwd.hpp>
#include <string>

namespace robocal {

CellConfig cellFromJson(const nlohmann::json& json, const std::string& source = "cell");
CellConfig parseCell(const std::string& text, const std::string& source = "cell");
nlohmann::ordered_json cellToJson(const CellConfig& cell);
CellConfig loadCellFile(const std::string& path);

}  // namespace robocal
