// The controller's nominal model for a command that compensates with a calibrated model
// (compensate, accuracy): the nominal recorded in the calibrated model when --nominal is not
// given; --nominal is then only a check, refused when it differs from the record, because
// compensating against another nominal than the calibration's gives wrong joints with no sign.
// A calibrated file older than the record falls back to --nominal, else to the built-in model of
// the name it was fitted from (robot/builtin.hpp), with a note on stderr; else it is refused.
#pragma once

#include "args.hpp"

#include <robocal/kinematics/model.hpp>

#include <optional>

namespace robocal::cli {

// `command` names the subcommand in notes ("compensate"); `model_key` is the option naming the
// calibrated model ("model", "calibrated"). Throws UsageError on a --nominal that differs, and
// when no nominal is found.
Model nominalFor(const Args& args, const Model& calibrated, const char* command,
                 const char* model_key);

// --approach-deg D: the one-sided approach's pre-point step (ModelProvenance::approach_deg), 0 to
// 1 deg; nullopt when not given. Throws UsageError out of range.
std::optional<double> approachDegArg(const Args& args);

// --payload-kg M (0 to 1000) and --payload-com x,y,z (mm, in the last link's frame): the work
// tool's weight in place of the calibration fixture's, for a model that carries its compliance
// (robocal solve --compliance). Leaves `model` unchanged when neither is given; throws
// UsageError on a bad value or a model with no compliance.
void applyPayloadArgs(const Args& args, Model& model);

}  // namespace robocal::cli
