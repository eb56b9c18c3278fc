// A model's frames for other tools (docs/export.md, "Frames JSON" and "DH table"): the chain as
// matrices a reader multiplies without knowing robocal's parameter conventions, and the standard
// DH table (kinematics/dh.hpp) with its stated error. No I/O: `robocal export --frames` and
// `--dh` write the text these return.
//
// Frames JSON (format "robocal-frames 1"), mm and deg:
//   chain: "T = L0 * Rz(theta1) * L1 * ... * Rz(theta6) * L6, theta_k = offset_deg_k +
//          gain_k * reading_k": links[0..6] as 4x4 row-major matrices (translation in mm) and as
//          translation_mm + quaternion_wxyz; joints[0..5] with offset_deg, gain, min_deg, max_deg,
//          and their axis and origin in the global frame at zero readings; balls_mm (in the tool
//          frame, after L6) and chucks_mm (global); dh: the DH table (below) with its error.
// DH table: CSV, one row per joint (joint,theta_offset_deg,d_mm,a_mm,alpha_deg,gain), after '#'
//   comment lines that state the convention, the base and tool transforms (4x4, row-major, mm),
//   the joints taken as parallel and the table's error against the model.
#pragma once

#include <robocal/kinematics/dh.hpp>
#include <robocal/kinematics/model.hpp>

#include <nlohmann/json.hpp>
#include <string>

namespace robocal {

nlohmann::ordered_json modelFramesJson(const Model& model, const DhTable& dh,
                                       const std::string& source = "");
// "joints taken as parallel: 2-3; against the model at 1000 joint vectors within the limits:
// position error <= 0.0870 mm, rotation <= 0.0097 deg".
std::string dhErrorSummary(const DhTable& dh);
std::string dhTableCsv(const Model& model, const DhTable& dh, const std::string& source = "");

}  // namespace robocal
