// The keys of a joint compliance, shared by the model file's "compliance" object
// (docs/model-format.md) and a truth's "realism" (docs/realism.md), so the two read the same:
//   compliance_deg_per_nm [6] (-0.1 to 0.1: a fitted one may be a little below 0), link_mass_kg [6]
//   (0 to 1000), link_com_mm [6][3], payload_kg (0 to 1000), payload_com_mm [3], gravity_direction
//   [3] (normalised, not zero).
#pragma once

#include <robocal/formats/error.hpp>
#include <robocal/jsonread/strict_json.hpp>
#include <robocal/kinematics/model.hpp>

#include <nlohmann/json.hpp>

namespace robocal {

// Six numbers in [lo, hi] under `key`, one per joint; `out` unchanged when the key is absent.
void readJointNumbers(jsonread::Object<FormatError>& o, const std::string& key,
                      std::array<double, kJointCount>& out, double lo, double hi);
// The compliance keys present in `o` into `c` (absent keys keep their values).
void readComplianceKeys(jsonread::Object<FormatError>& o, JointCompliance& c);
// The compliance keys of `c` into `out`.
void writeComplianceKeys(nlohmann::ordered_json& out, const JointCompliance& c);

}  // namespace robocal
