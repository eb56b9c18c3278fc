// The planner tests' shared inputs: the shipped nominal model and reference cell, read once.
#pragma once

#include <robocal/formats/model_json.hpp>
#include <robocal/planner/cell_json.hpp>

#include <string>

namespace robocal::test {

inline const std::string kSource = ROBOCAL_SOURCE_DIR;

inline const Model& nominal() {
  static const Model m = loadModelFile(kSource + "/config/puma560-paper.json");
  return m;
}

// The shipped reference cell as its file has it (config/cell.json).
inline const CellConfig& shippedCell() {
  static const CellConfig c = loadCellFile(kSource + "/config/cell.json");
  return c;
}

// The shipped cell's grid, shells, tool and margins with plain points: no approach pre-points,
// revisits or reference pose, which their own tests turn on (test_plan.cpp). The grid's tests
// count its points and steps.
inline const CellConfig& gridCell() {
  static const CellConfig c = [] {
    CellConfig plain = shippedCell();
    plain.motion.approach_deg = 0;
    plain.motion.revisit_every = 0;
    plain.motion.reference_every_min = 0;
    return plain;
  }();
  return c;
}

}  // namespace robocal::test
