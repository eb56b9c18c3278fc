// The fit of a completed shell set, on a worker thread of its own: robocal solve's assessment of
// the run's samples file, the calibrated model and the report written into the run folder, and a
// RESULT published (and kept for `result`), with the predicted error over the cell's work volume;
// the calibrated model is stored as a new version (ModelStore) for `activate`. At most one fit
// runs; the next waits for it.
#pragma once

#include "run_shared.hpp"

#include <robocal/daemon/model_store.hpp>
#include <robocal/daemon/run.hpp>
#include <robocal/daemon/run_store.hpp>
#include <robocal/kinematics/model.hpp>
#include <robocal/kinematics/sample.hpp>
#include <robocal/planner/cell.hpp>
#include <robocal/planner/plan.hpp>
#include <robocal/solver/health.hpp>

#include <future>
#include <vector>

namespace robocal::daemon {

class FitJob {
 public:
  FitJob(const Model& nominal, const WorkVolume& work_volume, const HealthOptions& health,
         ModelStore& models, RunShared& shared, RunController::Publish publish)
      : nominal_(nominal),
        work_volume_(work_volume),
        health_(health),
        models_(models),
        shared_(shared),
        publish_(std::move(publish)) {}
  ~FitJob() { wait(); }
  FitJob(const FitJob&) = delete;
  FitJob& operator=(const FitJob&) = delete;

  // Fits set `set_index` (its bar extension `set_extension_mm`) from the run's samples. `samples`
  // is what the run measured: the samples file is read back and fitted when it holds the same
  // number, so that the RESULT is `robocal solve --json` of that file.
  // `approach_deg` is the plan's motion.approach_deg, recorded in the model.
  void launch(RunDir dir, std::vector<Sample> samples, double set_extension_mm, int set_index,
              double approach_deg);
  // A health check run's end: its samples judged against the active model (solver/health.hpp);
  // the verdict goes to the run folder (check.json), the event log, the model's history and the
  // clients (CHECK).
  void launchCheck(RunDir dir, std::vector<Sample> samples);
  // An ISO 9283-style test run's end (planner/iso_plan.hpp): its figures against the nominal
  // model the plan was made with, written to the run folder (iso9283.json, iso9283.txt), the
  // event log, and the clients (an EVENT "iso_report" with the figures).
  void launchIso(RunDir dir, std::vector<Sample> samples, IsoTestSettings settings);
  void wait() {
    if (running_.valid()) running_.wait();
  }

 private:
  const Model& nominal_;
  const WorkVolume work_volume_;
  const HealthOptions health_;
  ModelStore& models_;
  RunShared& shared_;
  const RunController::Publish publish_;
  std::future<void> running_;
};

}  // namespace robocal::daemon
