// The run thread's toolbox: the cell (CellIo), the run's view of the bar, and the operations
// every part of a run uses (state changes, watched moves, measurements, the operator's prompts).
// Run thread only; what it shares with the client loop goes through RunShared.
#pragma once

#include "run_shared.hpp"

#include <robocal/daemon/cell_io.hpp>
#include <robocal/daemon/config.hpp>
#include <robocal/daemon/dwell_audit.hpp>
#include <robocal/daemon/run.hpp>
#include <robocal/daemon/run_store.hpp>
#include <robocal/daemon/steady_window.hpp>
#include <robocal/planner/cell.hpp>
#include <robocal/planner/plan.hpp>

#include <chrono>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace robocal::daemon {

// Why the run left the normal path. Pause and fault leave it resumable; abort does not.
struct StopRun {
  enum Kind { kPause, kFault, kAbort } kind;
  std::string reason;
};
// A fault of its own kind: the bar's reading moved with the robot while the bar was believed
// detached. A nudge at a connect prompt catches it (the operator seated the bar early).
struct DetachedBarMoved : StopRun {};

class RunContext {
 public:
  using Clock = std::chrono::steady_clock;

  RunContext(const DaemonConfig& config, const Model& nominal,
             const std::optional<CellConfig>& cell, RunController::Publish publish, RunStore& store,
             RunShared& shared, CellIo& io);

  const DaemonConfig& config;
  const Model& nominal;
  RunStore& store;
  RunShared& shared;
  CellIo& io;
  const RunController::Publish publish;

  const CellConfig& cellFor(const Plan& plan) const { return cell_ ? *cell_ : plan.cell; }

  // ---- state and events
  void setState(proto::RunState to, const std::string& reason = {});
  // Into the run's event log and out to watchers as an EVENT.
  void event(RunDir& dir, nlohmann::json ev);
  // Throws StopRun when a pause or an abort was asked for.
  void checkpoint();
  void updateProgress(int done, int total, double time_left_s);

  // ---- devices
  // Connects what is not connected and records the outcome for STATUS and `start`. Never throws.
  void connectDevices();
  // Before a run: both devices answer, or StopRun (fault) with the port's error.
  void ensureDevices();
  // The drivers' absorbed faults since the last report, into the event log as "link_faults".
  void reportLinkFaults(RunDir& dir);
  void forgetLinkFaults() { link_faults_reported_ = io.faultCounts(); }

  // ---- the bar
  // The bar may be attached from now on (or no longer): on disk before anything moves.
  void setAttachment(const BarAttachment& a);
  BarAttachment attachment() const;
  bool barMaybeAttached() const { return attachment().maybe_attached; }
  // Nominal length plus extension of the bar now attached (0: none).
  void setBarOffset(double length_mm) { bar_offset_mm_ = length_mm; }
  double barOffset() const { return bar_offset_mm_; }
  const std::optional<drivers::BarReading>& lastReading() const { return last_reading_; }
  // The median of the last few readings (nullopt before any): steadier than one reading.
  std::optional<double> recentReadingMm() const;
  void forgetReading() {
    last_reading_.reset();
    recent_readings_mm_.clear();
  }
  // Throws StopRun (fault) when the bar is out of range, silent, or past the hard limit; returns
  // the deflection when it is past the soft limit.
  std::optional<double> watchBar();
  // The same against another hard limit (a connect reading re-centred from past the run's own).
  std::optional<double> watchBar(double hard_limit_mm);

  // ---- moves and time
  // Pumps I/O (bar lines arrive) for a while / until a deadline, checking stop requests, and the
  // bar when `watch_bar`.
  void spin(double seconds, bool watch_bar);
  void spinUntil(Clock::time_point until, bool watch_bar);
  // The dwell at a data point, from the move's end, watched: settle_s (dwell_mode fixed), or until
  // the bar's readings are steady and never later than settle_s (adaptive; steady_window.hpp).
  // An audited adaptive dwell reads the window it would have ended with, then goes on to
  // settle_s (dwell_audit.hpp). Without a noise to judge against, or once the audits lost trust
  // in it, or where the adaptive dwell is not allowed (an ISO test's points), the dwell is fixed.
  struct Dwell {
    bool adaptive = false;     // judged by the readings' steadiness
    bool steady = false;       // the readings were steady before settle_s
    bool ended_early = false;  // ... and the dwell ended then (not audited)
    bool audited = false;      // audit_mean_mm holds the window read when they were steady
    double noise_mm = 0;       // the noise judged against
    double audit_mean_mm = 0;
    std::size_t audit_readings = 0;
  };
  Dwell dwell(Clock::time_point motion_end, bool adaptive_allowed);
  // A joint move watched for stop requests, controller errors and the bar: with the bar attached
  // its limits; believed detached, a reading that changes (the bar is still attached after all).
  JointsDeg move(const JointsDeg& target, bool bar_attached);
  // The same, the bar attached and watched against `hard_limit_mm`.
  JointsDeg move(const JointsDeg& target, bool bar_attached, double hard_limit_mm);
  // Through `path` as moveRecentring below, the bar attached and watched against its hard limit.
  JointsDeg moveThrough(const std::vector<JointsDeg>& path);
  // A move with the bar attached that stops where the bar passes its soft limit.
  struct Moved {
    JointsDeg joints_deg;
    std::optional<double> recentre_mm;  // the deflection that stopped it short
  };
  // Through `path` (vias, then a point) without stopping at its vias where the cell can
  // (CellIo::moveThrough).
  Moved moveRecentring(const std::vector<JointsDeg>& path);
  // A move with the bar believed detached, then a fresh reading after `wait_s`: did the bar
  // follow it (the move's own watch saw it, it ran over range, or the reading left `reference_mm`
  // by more than detached_change_mm)? The detach probe and the creeping nudge ask this.
  struct Followed {
    JointsDeg joints_deg;  // where the robot stands
    bool followed = false, over_range = false;
    double change_mm = 0;  // the fresh reading minus `reference_mm` (0 when either is missing)
  };
  Followed moveWatchingForBar(const JointsDeg& target, std::optional<double> reference_mm,
                              double wait_s);

  struct Measurement {
    JointsDeg joints_deg;
    double deflection_mm = 0;
    double spread_mm = 0;  // max - min of the window's readings (grows with their number)
    double noise_mm = 0;   // their standard deviation (0 with one reading): the bar's noise
    std::size_t readings = 0;
    Clock::time_point bar_window_start, where_end;
  };
  // The bar averaged over the window and the actual joints (WHERE) read within it, watched. The
  // window opens at once: the controller's answer does not delay it.
  Measurement measureHere() { return measureHere(config.bar_window_s); }
  Measurement measureHere(double window_s);

  // ---- the adaptive dwell's safeguards (docs/settling.md)
  // A window read with the robot still after a full settle_s (the connection check's): it
  // measures the bar reader's noise. Forgotten at each connection check's start.
  void noteStillWindow(const Measurement& m) { still_noise_.add(m.noise_mm, m.readings); }
  void forgetStillNoise() { still_noise_.clear(); }
  const StillNoise& stillNoise() const { return still_noise_; }
  // The noise the adaptive dwell judges steadiness against: bar_noise_mm when configured, else
  // the measured one; nullopt (a fixed dwell) with dwell_mode fixed, before a measurement, or
  // once the audits lost trust in the adaptive dwell.
  std::optional<double> adaptiveNoiseMm() const;
  // The noise measured since the last connection check began (nullopt: too few readings yet).
  std::optional<double> measuredNoiseMm() const;
  // An audited dwell's window against the fixed dwell's measurement `m` that followed it, judged
  // by the measured noise (bar_noise_mm when none is measured).
  DwellAudit::Verdict audit(const Dwell& d, const Measurement& m);
  bool adaptiveTrusted() const { return audit_.trusted(); }
  // A run starts or resumes: no noise measured yet (the next connection check measures it), the
  // audits afresh (the first steady dwell audited).
  void resetAdaptiveDwell() {
    still_noise_.clear();
    audit_ = DwellAudit{};
    steady_dwells_ = 0;
  }

  // ---- the operator
  // Publishes the PROMPT and waits for the operator's confirm; `on_nudge` (when given) carries out
  // nudge requests meanwhile.
  void waitConfirm(RunDir& dir, const proto::Prompt& prompt,
                   const std::function<void(double)>& on_nudge = {});
  // Asks to detach the bar (shell 0: at the end of the run) and records, once confirmed, that it
  // is off the robot.
  void waitDetach(RunDir& dir, int shell, const std::string& message);

 private:
  JointsDeg move(const std::vector<JointsDeg>& path, bool bar_attached, double hard_limit_mm);
  void onBarLine(const drivers::BarReading& r);
  // Before a window collects: what is queued delivered (and watched), then the window emptied.
  void clearWindow();
  // Believed detached: stops the move (StopRun) once the bar's readings have left the reference
  // taken before it (the bar is attached after all).
  void watchDetached();
  std::string stopReason(const std::string& fallback) const;

  const std::optional<CellConfig>& cell_;
  std::optional<drivers::BarReading> last_reading_;
  static constexpr std::size_t kReferenceReadings = 5;
  std::deque<double> recent_readings_mm_;  // the last readings, for a move's detached reference
  // While a move runs with the bar believed detached: how far the readings have left the
  // reference, and how many readings in a row were past the threshold.
  struct DetachedChange {
    double threshold_mm = 0;
    double change_mm = 0;
    int readings_past = 0;
    bool over_range = false;
    void add(const drivers::BarReading& r, double reference_mm);
  };
  std::optional<double> detached_reference_mm_;
  DetachedChange detached_;
  std::vector<double> window_;  // readings collected while averaging
  bool collecting_ = false;
  SteadyWindow* steady_ = nullptr;  // fed the readings during an adaptive dwell
  StillNoise still_noise_;
  DwellAudit audit_;
  long steady_dwells_ = 0;  // adaptive dwells whose readings were steady: every Nth is audited
  Clock::time_point dwell_start_{};
  double bar_offset_mm_ = 0;
  std::map<std::string, long> link_faults_reported_;
};

}  // namespace robocal::daemon
