// The planner tests' shared inputs: the shipped nominal model and reference cell, read once.
#pragma once

#include <robocal/formats/model_json.hpp>
#include <robocal/planner/cell_json.hpp>

#include <string>

namespace robocal::test {

inline const std::string kSource = ROBOCAL_SOURCE_DIR;

inline const Model& nominal() {
  static const Model m = loadModelFile(kSource + "/config/puma560.json");
  return m;
}

inline const CellConfig& defaultCell() {
  static const CellConfig c = loadCellFile(kSource + "/config/cell.json");
  return c;
}

}  // namespace robocal::test
