// The plan file (docs/plan-format.md): JSON with the settings used, a summary and the ordered
// shells with their connect pose and steps. Errors are FormatError naming the file and the key.
#pragma once

#include <robocal/formats/error.hpp>
#include <robocal/planner/plan.hpp>

#include <nlohmann/json_fwd.hpp>
#include <string>

namespace robocal {

inline constexpr const char* kPlanFormat = "robocal-plan";
inline constexpr int kPlanFormatVersion = 1;

nlohmann::ordered_json planToJson(const Plan& plan);
std::string formatPlan(const Plan& plan);  // pretty JSON text, ends with a newline
Plan planFromJson(const nlohmann::json& json, const std::string& source = "plan");
Plan parsePlan(const std::string& text, const std::string& source = "plan");
Plan loadPlanFile(const std::string& path);
void savePlanFile(const std::string& path, const Plan& plan);

}  // namespace robocal
