// The truth file of a simulation (docs/realism.md): a model file (docs/model-format.md) with an
// optional "realism" object, the effects of true_robot.hpp in interface units. Every model reader
// ignores "realism", so a truth file still reads as the true model's geometry; without it the true
// robot is ideal. Keys are checked strictly: an unknown or misspelt key, a wrong type or a value
// out of range is a FormatError naming the file and the key path.
#pragma once

#include <robocal/sim/true_robot.hpp>

#include <nlohmann/json_fwd.hpp>

#include <string>

namespace robocal {

Realism realismFromJson(const nlohmann::json& json, const std::string& source);
nlohmann::ordered_json realismToJson(const Realism& realism);

TrueRobot loadTruthFile(const std::string& path);
// A file holding a JSON object of realism keys alone (robocal simulate --realism FILE).
Realism loadRealismFile(const std::string& path);
// What a --realism option names: "ideal", "typical" (Realism::typical with the arm's masses,
// `arm_load`) or a realism file.
Realism realismNamed(const std::string& ideal_typical_or_path, const GravityLoad& arm_load);
void saveTruthFile(const std::string& path, const TrueRobot& truth);

}  // namespace robocal
