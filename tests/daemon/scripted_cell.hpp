// Test helper: a scripted cell behind the run controller's device seam (CellIo), in-process and
// without ports, so the run's state machine is tested in seconds. The robot moves at once (in a
// few steps, each watched); the bar reads the true distance from the chuck to the ball minus the
// bar's length while it is attached, and a constant while it is free. Faults are scripted: the
// Nth move throws a driver error. The pty/cellsim end-to-end tests stay the acceptance.
#pragma once

#include <robocal/daemon/cell_io.hpp>
#include <robocal/drivers/errors.hpp>
#include <robocal/kinematics/kinematics.hpp>

#include <mutex>
#include <optional>
#include <thread>

namespace robocal::test {

class ScriptedCell final : public daemon::CellIo {
 public:
  ScriptedCell(Model truth, double bar_length_mm, JointsDeg start)
      : truth_(std::move(truth)), bar_length_mm_(bar_length_mm), joints_(std::move(start)) {}

  // The same cell as a new daemon finds it: the robot where it stands, the bar as it is.
  std::unique_ptr<ScriptedCell> restarted() const {
    std::lock_guard lock(mutex_);
    auto next = std::make_unique<ScriptedCell>(truth_, bar_length_mm_, joints_);
    next->attached_ = attached_;
    next->ball_ = ball_;
    next->chuck_ = chuck_;
    next->extension_mm_ = extension_mm_;
    return next;
  }

  // The operator's hands (any thread).
  void attach(int ball, int chuck, double extension_mm) {
    std::lock_guard lock(mutex_);
    attached_ = true;
    ball_ = ball - 1;
    chuck_ = chuck - 1;
    extension_mm_ = extension_mm;
  }
  void detach() {
    std::lock_guard lock(mutex_);
    attached_ = false;
  }
  bool attached() const {
    std::lock_guard lock(mutex_);
    return attached_;
  }
  // The Nth move from now (1: the next) throws this error.
  void failMove(int nth, std::string what) {
    std::lock_guard lock(mutex_);
    fail_at_ = moves_ + nth;
    fail_what_ = std::move(what);
  }
  int moves() const {
    std::lock_guard lock(mutex_);
    return moves_;
  }
  // Moves made while the bar was attached, and the largest |deflection| seen during them.
  double worstDeflection() const {
    std::lock_guard lock(mutex_);
    return worst_mm_;
  }
  // A late reader: from now on each move leaves a reading of the arm half-way through it queued,
  // and the next poll() delivers it before anything newer, as a pty holds the lines a run thread
  // was too late to read while the arm moved.
  void queueReadingsInMotion() {
    std::lock_guard lock(mutex_);
    queue_in_motion_ = true;
  }
  int halts() const {
    std::lock_guard lock(mutex_);
    return halts_;
  }
  JointsDeg joints() const {
    std::lock_guard lock(mutex_);
    return joints_;
  }

  // CellIo (the run thread).
  void onBarLine(BarHandler handler) override { on_bar_ = std::move(handler); }
  daemon::DeviceState connect() override { return {true, true, {}, {}}; }
  bool barConnected() const override { return true; }
  bool barStale() const override { return false; }
  bool poll(Clock::time_point until) override {
    std::optional<drivers::BarReading> queued;
    {
      std::lock_guard lock(mutex_);
      queued.swap(queued_);
    }
    if (queued && on_bar_) on_bar_(*queued);
    emitReading();
    std::this_thread::sleep_until(std::min(until, Clock::now() + std::chrono::milliseconds(5)));
    return true;
  }
  JointsDeg where() override {
    std::lock_guard lock(mutex_);
    return joints_;
  }
  MoveOutcome move(const JointsDeg& target, const MoveWatch& watch) override {
    JointsDeg from;
    {
      std::lock_guard lock(mutex_);
      ++moves_;
      if (moves_ == fail_at_)
        throw drivers::ArmPowerOffError("the controller says: " + fail_what_, fail_what_);
      from = joints_;
    }
    constexpr int kSteps = 4;
    for (int k = 1; k <= kSteps; ++k) {
      {
        std::lock_guard lock(mutex_);
        joints_ = from + (target - from) * (static_cast<double>(k) / kSteps);
        if (queue_in_motion_ && k == kSteps / 2) queued_ = readingLocked();
      }
      emitReading();
      try {
        if (watch && watch()) {
          halt();
          return {where(), true};
        }
      } catch (...) {
        halt();
        throw;
      }
    }
    return {where(), false};
  }
  void halt() override {
    std::lock_guard lock(mutex_);
    ++halts_;
  }
  std::map<std::string, long> faultCounts() const override { return {}; }

 private:
  void emitReading() {
    drivers::BarReading r;
    {
      std::lock_guard lock(mutex_);
      r = readingLocked();
    }
    if (on_bar_) on_bar_(r);
  }
  // The bar's reading where the arm is now (the mutex held).
  drivers::BarReading readingLocked() {
    drivers::BarReading r;
    r.value_mm = kFreeReadingMm;
    if (attached_) {
      const Kinematics kin(truth_);
      const double distance_mm =
          (kin.ballPosition(joints_, truth_.balls_mm[ball_]) - truth_.chucks_mm[chuck_]).norm();
      r.value_mm = distance_mm - bar_length_mm_ - extension_mm_;
      worst_mm_ = std::max(worst_mm_, std::abs(r.value_mm));
    }
    r.sequence = ++sequence_;
    r.time = Clock::now();
    r.line = std::to_string(r.value_mm);
    return r;
  }

  static constexpr double kFreeReadingMm = 0.2;  // a free bar rests at its spring's end
  const Model truth_;
  const double bar_length_mm_;
  mutable std::mutex mutex_;
  JointsDeg joints_;
  bool attached_ = false;
  int ball_ = 0, chuck_ = 0;
  double extension_mm_ = 0;
  int moves_ = 0, fail_at_ = -1, halts_ = 0;
  std::string fail_what_;
  double worst_mm_ = 0;
  std::uint64_t sequence_ = 0;
  bool queue_in_motion_ = false;
  std::optional<drivers::BarReading> queued_;  // delivered by the next poll(), before the rest
  BarHandler on_bar_;
};

}  // namespace robocal::test
