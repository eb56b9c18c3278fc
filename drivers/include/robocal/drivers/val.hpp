// The Unimation VAL II controller over its monitor terminal: move to six joint angles, WHERE, set
// speed, abort. Owns prompt/echo/line-ending handling, per-command timeouts, motion completion
// (poll WHERE until at the target and still) and typed controller errors.
//
// The core is asynchronous on the io_context: a receive loop runs while connected (error lines
// the controller prints on its own, such as an E-stop, are seen when they arrive), commands are
// queued and each has its timer. The daemon uses the async* calls in its event loop. The
// synchronous calls (tests, the command line) start the same operations and run the io_context in
// the calling thread until they finish; do not call them from inside a handler of the same
// io_context.
#pragma once

#include <robocal/drivers/config.hpp>
#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/protocol.hpp>
#include <robocal/drivers/transport.hpp>

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace robocal::drivers {

struct ValStats {
  long commands = 0;
  long timeouts = 0;
  long controller_errors = 0;
  long unsolicited_lines = 0;      // received between commands (an E-stop message, late replies)
  long where_polls = 0;            // WHEREs sent while waiting for motions
  long where_retries = 0;          // of which asked again after an unreadable reply
  long ignored_lines = 0;          // dropped by val.ignore_regex (completion messages)
  long move_timeouts_watched = 0;  // move commands past their deadline, then watched by WHERE
};

// Decides from successive WHERE replies whether a move has ended (pure; used by the driver).
class MotionMonitor {
 public:
  enum class State { kMoving, kArrived, kStoppedShort, kTimedOut };
  MotionMonitor(const ValConfig& config, const Joints6& target, Clock::time_point start);
  State update(const Joints6& joints_deg, Clock::time_point now);
  // Why the move failed, for kStoppedShort and kTimedOut.
  std::string explain(State state, const Joints6& joints_deg) const;
  int unreadable = 0;  // WHERE replies in a row that could not be read (kept by the driver)

 private:
  const ValConfig& config_;
  Joints6 target_;
  Clock::time_point deadline_, moving_since_;
  std::optional<Joints6> previous_;
  int still_ = 0;
};

class ValController {
 public:
  using ReplyHandler = std::function<void(std::exception_ptr, std::vector<std::string>)>;
  using WhereHandler = std::function<void(std::exception_ptr, WhereReply)>;
  using ProgressHandler = std::function<void(const WhereReply&)>;

  ValController(boost::asio::io_context& io, ValConfig config);
  ~ValController();
  ValController(const ValController&) = delete;
  ValController& operator=(const ValController&) = delete;

  // Opens the port and wakes the monitor (an empty line) until it shows its prompt. PortError
  // when the port cannot be opened, TimeoutError when nothing answers.
  void connect();
  // Re-opens the port (e.g. after a USB adapter was re-plugged) retrying for up to within_s.
  void reconnect(double within_s);
  void disconnect();
  bool isConnected() const { return link_.isOpen() && !disconnected_; }

  // One command and its reply lines (echo, prompt and empty lines removed). Controller error
  // lines are thrown as ControllerError (ArmPowerOffError, OutOfRangeError); TimeoutError when
  // the prompt does not come back within timeout_s; DisconnectedError when the port goes away.
  std::vector<std::string> command(const std::string& text, double timeout_s);
  WhereReply where();
  void setSpeed(double percent);
  void abort();
  // Sends the move command only (the prompt may come back before the motion ends).
  void startMove(const Joints6& target_deg);
  // The move command's deadline (s): its echo within val.move_timeout_s, its prompt within
  // move_timeout_s plus the largest joint change from the
  // last WHERE at the slowest joint speed scaled by the last SPEED set; motion_timeout_s while
  // either is unknown.
  double moveCommandTimeout(const Joints6& target_deg) const;
  // Polls WHERE until the joints are within at_target_tol_deg of the target and still;
  // MotionError on motion_timeout_s or when the arm stops short for stopped_short_s.
  // `progress` (optional) sees every WHERE.
  WhereReply waitForMotion(const Joints6& target_deg, const ProgressHandler& progress = {});
  // startMove + waitForMotion.
  WhereReply moveJoints(const Joints6& target_deg, const ProgressHandler& progress = {});

  // Asynchronous forms: the handler runs on the io_context with the error (nullptr on success)
  // and the result. Commands are queued and sent one at a time.
  void asyncCommand(const std::string& text, double timeout_s, ReplyHandler handler);
  void asyncWhere(WhereHandler handler);
  void asyncMoveJoints(const Joints6& target_deg, WhereHandler handler,
                       ProgressHandler progress = {});
  // Motion through vias without stopping (val.path_*, docs/cell-time.md): writes a program through
  // `steps_deg` (the last is the target), one line at a time, each line only after the previous
  // one was accepted, runs it, and polls WHERE as a move does until the arm is still at the last
  // step. DriverError when the dialect offers no path program (offersPaths()) or a step is not a
  // number; a line the controller refuses ends it before anything runs (a refused MOVE line:
  // the editor is left with path_end_edit; a refused or lost EDIT or E is not followed by
  // anything, since a bare E at the monitor may be an abbreviation of EXECUTE). `progress` also
  // sees one WHERE between the program and its execution.
  bool offersPaths() const { return !dialect_.config().path_execute_command.empty(); }
  void asyncMovePath(const std::vector<Joints6>& steps_deg, WhereHandler handler,
                     ProgressHandler progress = {});
  WhereReply movePath(const std::vector<Joints6>& steps_deg, const ProgressHandler& progress = {});
  // Error lines the controller prints between commands (E-stop), as they arrive.
  void onUnsolicitedError(std::function<void(const std::string&)> callback) {
    unsolicited_callback_ = std::move(callback);
  }

  const ValDialect& dialect() const { return dialect_; }
  SerialLink& link() { return link_; }
  const ValStats& stats() const { return stats_; }
  // The prompt that ended the latest reply: VAL shows "*" while a program or DO runs.
  const std::string& lastPrompt() const { return last_prompt_; }

 private:
  struct Exchange;
  void received(std::string_view bytes);
  void replyComplete();
  void waitPromptQuiet(std::uint64_t id);
  void unsolicited(std::string_view bytes);
  void startNext();
  void waitQuiet(std::uint64_t id);
  void send();
  void waitDeadline(std::uint64_t id, Clock::time_point when);
  // A command whose echo must be back within echo_timeout_s and its reply within timeout_s.
  void asyncCommand(const std::string& text, double timeout_s, double echo_timeout_s,
                    ReplyHandler handler);
  void finish(std::exception_ptr error);
  void lost(const std::string& why);
  template <typename T>
  T runSync(const std::function<void(std::function<void(std::exception_ptr, T)>)>& start,
            double timeout_s);
  // One WHERE of a motion wait, then the next after poll_interval_s. `where_timeout_s` is the
  // first WHERE's: longer after a move command timed out (a controller busy with a synchronous
  // move answers when the motion ends).
  void pollMotion(std::shared_ptr<MotionMonitor> monitor, Joints6 target, WhereHandler handler,
                  ProgressHandler progress, double where_timeout_s);
  void asyncWhere(double timeout_s, WhereHandler handler);
  // A command that starts a motion to `target` (a DO MOVE, a path program's execute), then its
  // watch by WHERE. A synchronous controller's prompt comes back when the motion ends: past its
  // deadline with the echo seen, WHERE decides.
  void asyncMotionCommand(const std::string& text, double timeout_s, const Joints6& target,
                          WhereHandler handler, ProgressHandler progress);
  // The program lines of a path from `next` on, each after the previous one's reply.
  void sendPathLines(std::shared_ptr<std::vector<std::string>> lines, std::size_t next,
                     Joints6 target, double timeout_s, WhereHandler handler,
                     ProgressHandler progress);
  void leaveEditor(std::shared_ptr<std::vector<std::string>> lines, std::size_t failed,
                   std::exception_ptr error, WhereHandler handler);
  // moveCommandTimeout over a path: its joint travel step by step.
  double pathCommandTimeout(const std::vector<Joints6>& steps_deg) const;
  std::string describeTimeout(const std::string& command, double timeout_s,
                              const ValReplyCollector& reply) const;

  boost::asio::io_context& io_;
  ValDialect dialect_;
  SerialLink link_;
  boost::asio::steady_timer timer_, poll_timer_, quiet_timer_;
  ValStats stats_;
  std::shared_ptr<int> alive_;  // timer handlers hold a weak_ptr: they never outlive the controller
  bool disconnected_ = false, out_of_sync_ = false;
  std::string disconnect_reason_;
  Clock::time_point last_rx_{};
  std::unique_ptr<Exchange> current_;
  std::deque<std::unique_ptr<Exchange>> queue_;
  std::uint64_t exchange_id_ = 0;
  LineSplitter unsolicited_splitter_;
  std::vector<std::string> pending_errors_;
  std::function<void(const std::string&)> unsolicited_callback_;
  std::optional<Joints6> last_joints_;   // from the latest WHERE
  std::optional<double> speed_percent_;  // the latest SPEED the controller accepted
  std::string last_prompt_;
  bool controller_echoes_ = true;  // the last reply had the echo: move commands must see one
};

}  // namespace robocal::drivers
