// The calibration run: a state machine on its own thread that owns the two drivers (on the
// thread's own io_context). It checks the plan before anything moves, asks the operator for each
// connection, moves through the steps watching the bar, dwells, records every sample durably,
// keeps the bar centred by re-planning with a model refined from the data so far, and hands each
// completed shell set to the solver on a worker thread. Commands arrive from the client loop
// through thread-safe calls; events go back through `publish`.
#pragma once

#include <robocal/daemon/cell_io.hpp>
#include <robocal/daemon/config.hpp>
#include <robocal/daemon/model_store.hpp>
#include <robocal/daemon/run_store.hpp>
#include <robocal/kinematics/model.hpp>
#include <robocal/planner/plan.hpp>
#include <robocal/proto/objects.hpp>

#include <nlohmann/json.hpp>

#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace robocal::daemon {

class RunController {
 public:
  // Called from the run and solver threads; must be thread-safe (robocald posts to its loop).
  using Publish = std::function<void(nlohmann::json object, bool droppable)>;

  // `cell_io`: the cell to run on; the drivers of `config` when null (tests give a scripted one).
  RunController(DaemonConfig config, Model nominal, std::optional<CellConfig> cell, Publish publish,
                std::unique_ptr<CellIo> cell_io = nullptr);
  ~RunController();
  RunController(const RunController&) = delete;
  RunController& operator=(const RunController&) = delete;

  // Each returns an error message for the operator, or "" when accepted.
  std::string start(const Plan& plan);
  std::string confirm(std::optional<int> shell);
  // While a connect prompt waits: move the ball mm along the bar's line (+: away from the
  // chuck) so that the bar fits; at most 5 mm a time and 10 mm per prompt.
  std::string nudge(std::optional<int> shell, double mm);
  std::string pause(const std::string& reason);
  std::string resume(const std::string& run_id);
  // What a command did, for the operator: `error` when refused, else `message` says what happened.
  struct Answer {
    std::string error, message;
  };
  Answer abort(const std::string& reason);

  // The run's STATUS (the daemon adds its clients and plan).
  proto::Status status() const;
  nlohmann::json result() const;  // the latest RESULT object (or an empty one)
  nlohmann::json runs() const;    // a RUNS object
  // The latest CHECK (a health check's verdict; "available": false before the first).
  nlohmann::json checkResult() const;
  // The calibrated models the fits have stored (thread-safe; docs/robocald.md, "Models").
  ModelStore& models();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace robocal::daemon
