// The model file (docs/model-format.md): JSON with name, links[7], joints[6], balls[3], chucks[3],
// and for a calibrated model its provenance (optional; older files have none).
#pragma once

#include <robocal/formats/error.hpp>
#include <robocal/kinematics/model.hpp>

#include <nlohmann/json_fwd.hpp>

namespace robocal {

// Parses a model from JSON text; `source` names it in errors ("puma560.json: links[3].ry: ...").
Model parseModel(const std::string& text, const std::string& source = "model");
Model modelFromJson(const nlohmann::json& json, const std::string& source = "model");
nlohmann::ordered_json modelToJson(const Model& model);
std::string formatModel(const Model& model);  // pretty JSON text, ends with a newline

Model loadModelFile(const std::string& path);
void saveModelFile(const std::string& path, const Model& model);

}  // namespace robocal
