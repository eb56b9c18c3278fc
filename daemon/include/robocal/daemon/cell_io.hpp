// The cell as the run thread sees it: a robot that moves, says where it is and stops, and a
// ball-bar whose lines arrive while the run pumps I/O. Everything here is called from the run
// thread only. The real cell (makeDriverCell) wraps the VAL II and ball-bar drivers on one
// io_context; tests give the run controller a scripted cell instead, so the state machine runs in
// milliseconds without ports (the pty end-to-end tests stay the acceptance for the whole).
#pragma once

#include <robocal/drivers/bar.hpp>
#include <robocal/kinematics/model.hpp>

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace robocal::daemon {

struct DaemonConfig;

// Which devices answer, and why one does not ("" when it does).
struct DeviceState {
  bool val_connected = false, bar_connected = false;
  std::string val_error, bar_error;
};

class CellIo {
 public:
  using Clock = std::chrono::steady_clock;
  using BarHandler = std::function<void(const drivers::BarReading&)>;
  // Called while a move runs (after each position poll); true stops the move.
  using MoveWatch = std::function<bool()>;
  struct MoveOutcome {
    JointsDeg joints_deg;  // where the robot is at the end
    bool stopped = false;  // the watch stopped it short of the target (the robot is halted)
  };

  virtual ~CellIo() = default;
  // Every ball-bar line goes here, from within poll(), move() and where().
  virtual void onBarLine(BarHandler handler) = 0;
  // Connects what is not connected; never throws. The log says each change (connected, or why
  // not).
  virtual DeviceState connect() = 0;
  virtual bool barConnected() const = 0;
  // The bar has been silent longer than its stale_after_s.
  virtual bool barStale() const = 0;
  // Delivers what has already arrived, even when `until` has passed, then what arrives until
  // `until`; false when nothing could arrive (no device open).
  virtual bool poll(Clock::time_point until) = 0;
  virtual JointsDeg where() = 0;
  // Moves and waits for the end of the move; driver errors (a controller error, an E-stop, a
  // timeout) are thrown as drivers::DriverError. An exception from the watch ends the move too and
  // goes on to the caller; the robot is then halted first.
  virtual MoveOutcome move(const JointsDeg& target, const MoveWatch& watch) = 0;
  // Moves through `path` (the last step is where the arm comes to rest) without stopping at the
  // steps before it where the controller can (a path program, val.path_*); otherwise, and for
  // one step, one move() a step. The watch and the errors as move(); a watch that stops it stops
  // the whole path.
  virtual MoveOutcome moveThrough(const std::vector<JointsDeg>& path, const MoveWatch& watch) {
    if (path.empty()) return {where(), false};
    MoveOutcome out;
    for (const JointsDeg& step : path)
      if (out = move(step, watch); out.stopped) break;
    return out;
  }
  // Halts the robot (the controller's ABORT); never throws.
  virtual void halt() = 0;
  // The drivers' counters of faults they absorbed (garbled lines, retries, timeouts), by name.
  virtual std::map<std::string, long> faultCounts() const = 0;
};

// The real cell: the VAL II controller and the ball-bar reader of `config.drivers`.
std::unique_ptr<CellIo> makeDriverCell(const DaemonConfig& config);

}  // namespace robocal::daemon
