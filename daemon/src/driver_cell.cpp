// The real cell behind CellIo: the VAL II and ball-bar drivers on the run thread's io_context.
#include <robocal/daemon/cell_io.hpp>
#include <robocal/daemon/config.hpp>

#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/val.hpp>

#include <spdlog/spdlog.h>
#include <boost/asio/io_context.hpp>

namespace robocal::daemon {
namespace {

drivers::Joints6 toDriver(const JointsDeg& q) {
  drivers::Joints6 out{};
  for (int j = 0; j < kJointCount; ++j) out[j] = q[j];
  return out;
}
JointsDeg fromDriver(const drivers::Joints6& q) {
  JointsDeg out;
  for (int j = 0; j < kJointCount; ++j) out[j] = q[j];
  return out;
}

std::string describePort(const drivers::SerialConfig& port) {
  if (!port.path.empty()) return port.path;
  if (!port.usb_serial.empty()) return "USB serial " + port.usb_serial;
  return "USB description \"" + port.usb_description + "\"";
}

// Connects one device and logs a change of its state; the error, or "" when connected.
std::string attempt(const char* name, const drivers::SerialConfig& port, bool was_connected,
                    const std::string& old_error, const std::function<void()>& connect) {
  std::string error;
  try {
    connect();
  } catch (const std::exception& e) {
    error = e.what();
    if (error.empty()) error = "cannot connect";
  }
  if (error.empty() && !was_connected)
    spdlog::info("{} connected ({})", name, describePort(port));
  else if (!error.empty() && (was_connected || error != old_error))
    spdlog::warn("{} not connected ({}): {}", name, describePort(port), error);
  return error;
}

// How a watch that asks to stop ends the driver's move: thrown from the progress callback (which
// the driver lets through) and caught in move() below, never seen outside this file.
struct StopTheMove {};

class DriverCell final : public CellIo {
 public:
  explicit DriverCell(const drivers::DriversConfig& config) : config_(config) {}

  void onBarLine(BarHandler handler) override { on_bar_ = std::move(handler); }

  DeviceState connect() override {
    DeviceState now;
    now.bar_error = attempt("ball-bar reader", config_.bar.serial, bar_ && bar_->isConnected(),
                            last_.bar_error, [&] {
                              if (!bar_) {
                                bar_ = std::make_unique<drivers::BarReader>(io_, config_.bar);
                                bar_->onLine([this](const drivers::BarReading& r) {
                                  if (on_bar_) on_bar_(r);
                                });
                              }
                              if (!bar_->isConnected()) bar_->connect();
                            });
    now.val_error = attempt("VAL II controller", config_.val.serial, val_ && val_->isConnected(),
                            last_.val_error, [&] {
                              if (!val_)
                                val_ = std::make_unique<drivers::ValController>(io_, config_.val);
                              if (!val_->isConnected()) val_->connect();
                            });
    now.bar_connected = bar_ && bar_->isConnected();
    now.val_connected = val_ && val_->isConnected();
    last_ = now;
    return now;
  }

  bool barConnected() const override { return bar_ && bar_->isConnected(); }
  bool barStale() const override { return bar_ && bar_->isStale(); }

  bool poll(Clock::time_point until) override {
    io_.restart();
    io_.poll();  // run_until does nothing once `until` has passed, not even what is ready
    io_.restart();
    io_.run_until(until);
    return !io_.stopped();  // stopped: no port open, nothing to wait for
  }

  JointsDeg where() override { return fromDriver(controller().where().joints_deg); }

  MoveOutcome move(const JointsDeg& target, const MoveWatch& watch) override {
    return watched(watch, [&](const drivers::ValController::ProgressHandler& progress) {
      return controller().moveJoints(toDriver(target), progress);
    });
  }

  MoveOutcome moveThrough(const std::vector<JointsDeg>& path, const MoveWatch& watch) override {
    if (path.size() < 2 || !controller().offersPaths()) {
      if (path.size() > 1 && !warned_no_paths_) {
        warned_no_paths_ = true;
        spdlog::warn(
            "the plan moves through vias, but the controller's dialect has no path program "
            "(val.path_execute_command): every via is a stop, and the run takes longer than "
            "planned");
      }
      return CellIo::moveThrough(path, watch);
    }
    std::vector<drivers::Joints6> steps;
    for (const JointsDeg& q : path) steps.push_back(toDriver(q));
    return watched(watch, [&](const drivers::ValController::ProgressHandler& progress) {
      return controller().movePath(steps, progress);
    });
  }

  void halt() override {
    if (!val_ || !val_->isConnected()) return;
    try {
      val_->abort();
    } catch (const std::exception& e) {
      spdlog::error("ABORT failed: {}", e.what());
    }
  }

  std::map<std::string, long> faultCounts() const override {
    std::map<std::string, long> c;
    if (bar_) {
      const drivers::BarStats& b = bar_->stats();
      c["bar_garbage_lines"] = b.garbage_lines;
      c["bar_partial_lines"] = b.partial_lines;
      c["bar_timeouts"] = b.timeouts;
      c["bar_disconnects"] = b.disconnects;
      c["bar_device_errors"] = b.device_errors;
    }
    if (val_) {
      const drivers::ValStats& v = val_->stats();
      c["val_timeouts"] = v.timeouts;
      c["val_controller_errors"] = v.controller_errors;
      c["val_where_retries"] = v.where_retries;
      c["val_unsolicited_lines"] = v.unsolicited_lines;
    }
    return c;
  }

 private:
  // A driver motion watched after each WHERE: a watch that asks to stop halts the arm.
  template <typename Motion>
  MoveOutcome watched(const MoveWatch& watch, const Motion& motion) {
    try {
      const drivers::WhereReply w = motion([&](const drivers::WhereReply&) {
        if (watch && watch()) throw StopTheMove{};
      });
      return {fromDriver(w.joints_deg), false};
    } catch (const StopTheMove&) {
      halt();
      return {where(), true};
    } catch (const drivers::DriverError&) {
      throw;
    } catch (...) {
      halt();  // the watch refused to go on: nothing moves on after it
      throw;
    }
  }

  drivers::ValController& controller() {
    if (!val_ || !val_->isConnected())
      throw drivers::DisconnectedError("the VAL II controller is not connected");
    return *val_;
  }

  drivers::DriversConfig config_;
  boost::asio::io_context io_;
  std::unique_ptr<drivers::ValController> val_;
  std::unique_ptr<drivers::BarReader> bar_;
  BarHandler on_bar_;
  DeviceState last_;
  bool warned_no_paths_ = false;
};

}  // namespace

std::unique_ptr<CellIo> makeDriverCell(const DaemonConfig& config) {
  return std::make_unique<DriverCell>(config.drivers);
}

}  // namespace robocal::daemon
