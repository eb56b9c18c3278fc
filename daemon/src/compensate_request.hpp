// The `compensate` request: corrected joints for a list of targets with the active model
// (docs/protocol.md). It computes and moves nothing, so it needs no token. Called on the client
// loop: a request holds at most proto::kMaxCompensateTargets targets (about 1 ms each).
#pragma once

#include <robocal/daemon/model_store.hpp>
#include <robocal/proto/objects.hpp>

#include <nlohmann/json.hpp>

namespace robocal::daemon {

// A COMPENSATED object, or an ERROR naming what is missing (no active model) or wrong.
nlohmann::json compensateRequest(const ModelStore& models, const Model& nominal,
                                 const proto::Request& request);

}  // namespace robocal::daemon
