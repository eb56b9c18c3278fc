// What the client loop and the run thread both touch, and the one door to it: `with` runs a
// function on the data under the mutex. Nothing else in the run controller is shared; the
// run thread's own state lives in RunContext, the solver's in FitJob.
#pragma once

#include <robocal/daemon/cell_io.hpp>
#include <robocal/daemon/run_store.hpp>
#include <robocal/planner/plan.hpp>
#include <robocal/proto/objects.hpp>
#include <robocal/proto/protocol.hpp>

#include <nlohmann/json.hpp>

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace robocal::daemon {

// A run to start or resume, handed from a client's command to the run thread.
struct RunJob {
  enum Kind { kStart, kResume, kClose } kind;  // kClose: abort a paused or interrupted run
  Plan plan;                                   // kStart
  std::string run_id;                          // kResume, kClose
};

// A run in the history (`runs`), as its state.json says.
struct RunSummary {
  std::string run, status, reason;
};

struct RunData {
  std::optional<RunJob> job;
  // A start or resume the run thread has taken but not yet given a state (it creates the run
  // folder first): busy, so a second start in that gap is refused.
  bool starting = false;
  proto::RunState state = proto::RunState::kIdle;
  std::string state_reason;
  std::string run_id;        // current or last run
  std::string resumable_id;  // a paused or interrupted run
  std::string stop_reason;   // the operator's words for a pause or abort request
  // The operator.
  std::optional<proto::Prompt> prompt;  // the pending PROMPT
  int prompt_shell = 0;
  int confirms = 0;                   // counts confirm commands; the run waits for a change
  std::optional<double> nudge_mm;     // requested, not yet done
  double nudged_mm = 0;               // done for the pending prompt
  std::optional<double> free_bar_mm;  // the bar's reading off the robot, at the connect prompt
  // Progress.
  int shell_number = 0, shells_total = 0, points_done = 0, points_total = 0;
  double eta_s = 0;
  std::string connection_name;  // the shell's connection, e.g. "B1C3"
  // Devices and results.
  std::optional<proto::Bar> latest_bar;
  nlohmann::json last_result;
  nlohmann::json last_check;  // the latest CHECK (a health check's verdict), null before one
  DeviceState devices;
  BarAttachment attachment;      // persisted in <data_dir>/bar.json
  std::vector<RunSummary> runs;  // oldest first; kept by the run thread as it writes them

  bool busy() const { return proto::isBusy(state) || job.has_value() || starting; }
};

class RunShared {
 public:
  template <typename F>
  auto with(F&& f) {
    std::lock_guard lock(mutex_);
    return f(data_);
  }
  template <typename F>
  auto with(F&& f) const {
    std::lock_guard lock(mutex_);
    return f(static_cast<const RunData&>(data_));
  }
  // The run thread waits here when it has nothing to do; a new job wakes it.
  void wake() { wake_.notify_all(); }
  void waitFor(std::chrono::milliseconds ms) {
    std::unique_lock lock(mutex_);
    wake_.wait_for(lock, ms);
  }

  // Requests the run thread checks at its checkpoints (no lock needed).
  std::atomic<bool> abort_requested{false}, pause_requested{false}, quit{false};

 private:
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  RunData data_;
};

}  // namespace robocal::daemon
