// The nominal models robocal carries in code, found by name. A command that needs a controller's
// nominal and has no file for it (a calibrated model older than the recorded nominal) asks here,
// and is refused rather than given another arm's model. No I/O.
#pragma once

#include <robocal/kinematics/model.hpp>

#include <optional>
#include <string>

namespace robocal {

// The built-in nominal model named `name` exactly (Model::name); nullopt when robocal has none.
std::optional<Model> builtinNominalModel(const std::string& name);
// The built-in models' names, quoted and comma-separated, for messages.
std::string builtinNominalNames();

}  // namespace robocal
