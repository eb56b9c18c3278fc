// The Unimation VAL II controller over its monitor terminal: move to six joint angles, WHERE, set
// speed, abort. Owns prompt/echo/line-ending handling, per-command timeouts, motion completion
// (poll WHERE until at the target and still) and typed controller errors.
//
// The calls are synchronous: each runs the io_context in the calling thread until the reply, the
// deadline or an error. Do not call them from inside a handler of the same io_context.
#pragma once

#include <robocal/drivers/config.hpp>
#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/protocol.hpp>
#include <robocal/drivers/transport.hpp>

#include <boost/asio/io_context.hpp>

#include <functional>
#include <string>
#include <vector>

namespace robocal::drivers {

struct ValStats {
  long commands = 0;
  long timeouts = 0;
  long controller_errors = 0;
  long unsolicited_lines = 0;  // received between commands (an E-stop message, late replies)
  long where_polls = 0;        // WHEREs sent while waiting for motions
};

class ValController {
 public:
  ValController(boost::asio::io_context& io, ValConfig config);

  // Opens the port and wakes the monitor (an empty line) until it shows its prompt. PortError
  // when the port cannot be opened, TimeoutError when nothing answers.
  void connect();
  // Re-opens the port (e.g. after a USB adapter was re-plugged) retrying for up to within_s.
  void reconnect(double within_s);
  void disconnect();
  bool isConnected() const { return link_.isOpen(); }

  // One command and its reply lines (echo, prompt and empty lines removed). Controller error
  // lines are thrown as ControllerError (ArmPowerOffError, OutOfRangeError); TimeoutError when
  // the prompt does not come back within timeout_s; DisconnectedError when the port goes away.
  std::vector<std::string> command(const std::string& text, double timeout_s);

  WhereReply where();
  void setSpeed(double percent);
  void abort();
  // Sends the move command only (the prompt may come back before the motion ends).
  void startMove(const Joints6& target_deg);
  // Polls WHERE until the joints are within at_target_tol_deg of the target and still;
  // MotionError on motion_timeout_s or when the arm stops short for stopped_short_s.
  // `progress` (optional) sees every WHERE.
  WhereReply waitForMotion(const Joints6& target_deg,
                           const std::function<void(const WhereReply&)>& progress = {});
  // startMove + waitForMotion.
  WhereReply moveJoints(const Joints6& target_deg,
                        const std::function<void(const WhereReply&)>& progress = {});

  const ValDialect& dialect() const { return dialect_; }
  SerialLink& link() { return link_; }
  const ValStats& stats() const { return stats_; }

 private:
  void drainUnsolicited();

  boost::asio::io_context& io_;
  ValDialect dialect_;
  SerialLink link_;
  ValStats stats_;
  bool out_of_sync_ = false;
  std::vector<std::string> pending_errors_;
};

}  // namespace robocal::drivers
