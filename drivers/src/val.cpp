#include <robocal/drivers/val.hpp>

#include <boost/asio/post.hpp>
#include <boost/asio/write.hpp>

#include <algorithm>
#include <cmath>

namespace robocal::drivers {

namespace {

constexpr auto kQuiet = std::chrono::milliseconds(80);  // silence that ends a resync drain

std::string describeJoints(const Joints6& j) {
  std::string s;
  for (double v : j) s += (s.empty() ? "" : " ") + formatFixed(v, 3);
  return s;
}

double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

Clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

template <typename E>
std::exception_ptr errorPtr(const E& e) {
  return std::make_exception_ptr(e);
}

}  // namespace

// ------------------------------------------------------------------------------- MotionMonitor

MotionMonitor::MotionMonitor(const ValConfig& config, const Joints6& target,
                             Clock::time_point start)
    : config_(config),
      target_(target),
      deadline_(start + seconds(config.motion_timeout_s)),
      moving_since_(start) {}

MotionMonitor::State MotionMonitor::update(const Joints6& joints, Clock::time_point now) {
  if (previous_ && maxJointDiffDeg(joints, *previous_) <= config_.still_tol_deg) {
    ++still_;
  } else {
    still_ = 0;
    moving_since_ = now;
  }
  previous_ = joints;
  if (still_ >= config_.still_polls) {
    if (maxJointDiffDeg(joints, target_) <= config_.at_target_tol_deg) return State::kArrived;
    if (now - moving_since_ >= seconds(config_.stopped_short_s)) return State::kStoppedShort;
  }
  if (now >= deadline_) return State::kTimedOut;
  return State::kMoving;
}

std::string MotionMonitor::explain(State state, const Joints6& joints) const {
  const std::string where = ": at " + describeJoints(joints) + ", target " +
                            describeJoints(target_) + " (" +
                            formatFixed(maxJointDiffDeg(joints, target_), 3) + " deg off)";
  if (state == State::kStoppedShort)
    return "the arm stopped short of the target and stayed still for " +
           formatFixed(config_.stopped_short_s, 1) +
           " s (E-stop, a collision, or a move the controller dropped)" + where;
  return "the arm did not reach the target within " + formatFixed(config_.motion_timeout_s, 1) +
         " s" + where;
}

// ------------------------------------------------------------------------------- ValController

struct ValController::Exchange {
  Exchange(const ValDialect& dialect, std::string command, double timeout, double echo_timeout,
           ReplyHandler h)
      : text(std::move(command)),
        timeout_s(timeout),
        echo_timeout_s(echo_timeout),
        collector(dialect, text),
        handler(std::move(h)) {}
  std::string text;
  double timeout_s;
  double echo_timeout_s;  // the echo must be back by then, even when the reply may take longer
  ValReplyCollector collector;
  ReplyHandler handler;
  std::string bytes;  // what is sent: text and the line ending
  Clock::time_point deadline{};
  bool sent = false;
};

ValController::ValController(boost::asio::io_context& io, ValConfig config)
    : io_(io),
      dialect_(std::move(config)),
      link_(io, dialect_.config().serial),
      timer_(io),
      poll_timer_(io),
      quiet_timer_(io) {
  validate(dialect_.config());
}

ValController::~ValController() {
  alive_.reset();
  link_.close();
}

void ValController::connect() {
  disconnect();
  link_.open();
  alive_ = std::make_shared<int>(0);
  disconnected_ = false;
  disconnect_reason_.clear();
  out_of_sync_ = true;  // skip whatever the controller still prints from before
  last_rx_ = Clock::now();
  pending_errors_.clear();
  unsolicited_splitter_.clear();
  // The link keeps receiving even if a handler called from received() throws (a caller's
  // progress callback stopping a move).
  link_.receive(
      [this](std::string_view bytes) {
        last_rx_ = Clock::now();
        received(bytes);
      },
      [this](const std::string& why) { lost(why); });
  try {
    command("", dialect_.config().connect_timeout_s);
  } catch (const TimeoutError& e) {
    throw TimeoutError(std::string(e.what()) +
                       " (no prompt after waking the monitor with an empty line)");
  }
}

void ValController::reconnect(double within_s) {
  reconnectWithin(
      within_s, "the controller", [this] { connect(); }, [this] { disconnect(); });
}

void ValController::disconnect() {
  alive_.reset();  // orphans every pending handler
  timer_.cancel();
  poll_timer_.cancel();
  quiet_timer_.cancel();
  link_.close();
  const auto fail = [](std::unique_ptr<Exchange>& x) {
    if (x && x->handler)
      x->handler(errorPtr(DisconnectedError("the controller was disconnected")), {});
  };
  std::unique_ptr<Exchange> current = std::move(current_);
  auto queue = std::move(queue_);
  queue_.clear();
  fail(current);
  for (auto& x : queue) fail(x);
}

void ValController::lost(const std::string& why) {
  disconnected_ = true;
  disconnect_reason_ = link_.disconnected(why).what();
  if (current_) finish(errorPtr(DisconnectedError(disconnect_reason_)));
  while (!queue_.empty()) {
    auto x = std::move(queue_.front());
    queue_.pop_front();
    if (x->handler) x->handler(errorPtr(DisconnectedError(disconnect_reason_)), {});
  }
}

void ValController::received(std::string_view bytes) {
  if (!current_ || !current_->sent) {
    unsolicited(bytes);
    return;
  }
  if (current_->collector.feed(bytes)) return replyComplete();
  if (current_->collector.tentative()) waitPromptQuiet(exchange_id_);
}

void ValController::replyComplete() {
  // What followed the reply in the same read was printed after it: an error there (an E-stop)
  // is reported with this reply rather than lost.
  unsolicited(current_->collector.rest());
  finish(nullptr);
}

// A "*" at the end may be the busy prompt or the start of "*Arm power off*": the reply ends
// when nothing more comes for kPromptQuietMs (a new byte re-arms or settles it).
void ValController::waitPromptQuiet(std::uint64_t id) {
  std::weak_ptr<int> alive = alive_;
  quiet_timer_.expires_after(std::chrono::milliseconds(kPromptQuietMs));
  quiet_timer_.async_wait([this, alive, id](const boost::system::error_code& ec) {
    if (ec || alive.expired() || !current_ || exchange_id_ != id) return;
    if (current_->collector.quiet()) replyComplete();
  });
}

void ValController::unsolicited(std::string_view bytes) {
  std::vector<std::string> lines;
  unsolicited_splitter_.feed(bytes, lines);
  for (const auto& l : lines) {
    if (trim(l).empty()) continue;
    if (dialect_.isIgnored(trim(l))) {
      ++stats_.ignored_lines;
      continue;
    }
    ++stats_.unsolicited_lines;
    if (auto msg = dialect_.errorMessage(trim(l))) {
      pending_errors_.push_back(*msg);
      if (unsolicited_callback_) unsolicited_callback_(*msg);
    }
  }
}

void ValController::asyncCommand(const std::string& text, double timeout_s, ReplyHandler handler) {
  asyncCommand(text, timeout_s, timeout_s, std::move(handler));
}

void ValController::asyncCommand(const std::string& text, double timeout_s, double echo_timeout_s,
                                 ReplyHandler handler) {
  auto x =
      std::make_unique<Exchange>(dialect_, text, timeout_s, echo_timeout_s, std::move(handler));
  x->bytes = text + dialect_.config().send_line_ending;
  if (!isConnected()) {
    const std::string why = disconnect_reason_.empty()
                                ? "the controller port " + link_.describe() + " is not open"
                                : disconnect_reason_;
    boost::asio::post(
        io_, [h = std::move(x->handler), why] { h(errorPtr(DisconnectedError(why)), {}); });
    return;
  }
  queue_.push_back(std::move(x));
  if (!current_) startNext();
}

void ValController::startNext() {
  if (current_ || queue_.empty()) return;
  if (disconnected_ || !link_.isOpen()) {
    auto queue = std::move(queue_);
    queue_.clear();
    for (auto& x : queue)
      if (x->handler) x->handler(errorPtr(DisconnectedError(disconnect_reason_)), {});
    return;
  }
  current_ = std::move(queue_.front());
  queue_.pop_front();
  ++stats_.commands;
  const std::uint64_t id = ++exchange_id_;
  current_->deadline = deadlineAfter(current_->timeout_s);
  if (!out_of_sync_) {
    send();
    return;
  }
  // After a timeout or an error, let a late reply finish arriving (and be discarded) first.
  waitQuiet(id);
}

void ValController::waitQuiet(std::uint64_t id) {
  if (!current_ || exchange_id_ != id) return;
  const auto now = Clock::now();
  if (now - last_rx_ >= kQuiet || now >= current_->deadline) {
    send();
    return;
  }
  std::weak_ptr<int> alive = alive_;
  timer_.expires_at(last_rx_ + kQuiet);
  timer_.async_wait([this, alive, id](const boost::system::error_code& ec) {
    if (!ec && !alive.expired()) waitQuiet(id);
  });
}

void ValController::send() {
  current_->sent = true;
  out_of_sync_ = false;
  unsolicited_splitter_.clear();
  const std::uint64_t id = exchange_id_;
  std::weak_ptr<int> alive = alive_;
  // The bytes live as long as the write, even if the exchange ends first (a timeout).
  auto bytes = std::make_shared<std::string>(current_->bytes);
  boost::asio::async_write(link_.stream(), boost::asio::buffer(*bytes),
                           [this, alive, bytes](const boost::system::error_code& ec, std::size_t) {
                             if (alive.expired()) return;
                             if (ec && ec != boost::asio::error::operation_aborted)
                               lost(ec.message());
                           });
  // A long reply (a synchronous move) is waited for only once the echo has shown the command
  // arrived: a lost command is found after echo_timeout_s, not after the whole move's time.
  // A controller seen not to echo gets the whole time.
  const auto echo_deadline = std::min(current_->deadline, deadlineAfter(current_->echo_timeout_s));
  waitDeadline(id, controller_echoes_ ? echo_deadline : current_->deadline);
}

void ValController::waitDeadline(std::uint64_t id, Clock::time_point when) {
  std::weak_ptr<int> alive = alive_;
  timer_.expires_at(when);
  timer_.async_wait([this, alive, id](const boost::system::error_code& ec) {
    if (ec || alive.expired() || !current_ || exchange_id_ != id) return;
    const ValReplyCollector& reply = current_->collector;
    if ((reply.echoSeen() || !controller_echoes_) && Clock::now() < current_->deadline)
      return waitDeadline(id, current_->deadline);
    ++stats_.timeouts;
    out_of_sync_ = true;
    const double waited_s = reply.echoSeen()
                                ? current_->timeout_s
                                : std::min(current_->timeout_s, current_->echo_timeout_s);
    finish(errorPtr(
        CommandTimeoutError(describeTimeout(current_->text, waited_s, reply), reply.echoSeen())));
  });
}

// What was seen, in the order a technician checks it; advice only where it fits.
std::string ValController::describeTimeout(const std::string& command, double timeout_s,
                                           const ValReplyCollector& reply) const {
  std::string what = "no answer from the controller on " + link_.describe() + " to \"" + command +
                     "\" within " + formatFixed(timeout_s, 1) + " s";
  const std::string& raw = reply.raw();
  if (raw.empty())
    return what + ": nothing came back. Is it powered on and at the monitor prompt (" +
           dialect_.describePrompts() + "), the cable a null-modem one, and the baud rate right?";
  if (!looksLikeText(raw))
    return what + ": it sent bytes that are not text (" + escapeBytes(raw.substr(0, 40)) +
           "): wrong baud rate or parity, or a garbling USB adapter";
  what += ": it sent \"" + escapeBytes(raw.substr(0, 120)) + "\"";
  // The last text without a line ending is what the terminal shows now.
  std::string last =
      raw.substr(raw.find_last_of("\r\n") == std::string::npos ? 0 : raw.find_last_of("\r\n") + 1);
  last = trim(last);
  if (!last.empty() && last.size() <= 4)
    return what + "; it shows '" + last + "', which is not one of the configured prompts (" +
           dialect_.describePrompts() + "): if that is its prompt, add it to val.prompt";
  if (reply.echoSeen())
    return what + "; the command was echoed, then no prompt (" + dialect_.describePrompts() +
           ") came back";
  return what + "; no echo of the command and no prompt (" + dialect_.describePrompts() + ")";
}

void ValController::finish(std::exception_ptr error) {
  timer_.cancel();
  quiet_timer_.cancel();
  std::unique_ptr<Exchange> x = std::move(current_);
  std::vector<std::string> lines;
  stats_.ignored_lines += x->collector.ignored();
  if (!error) {
    last_prompt_ = x->collector.prompt();
    if (!x->text.empty()) controller_echoes_ = x->collector.echoSeen();  // not a wake-up
  }
  if (!error) {
    std::vector<std::string> errors = std::move(pending_errors_);
    pending_errors_.clear();
    errors.insert(errors.end(), x->collector.errors().begin(), x->collector.errors().end());
    if (!errors.empty()) {
      ++stats_.controller_errors;
      out_of_sync_ = true;  // an unsolicited error may have cut a reply short: drain first
      try {
        dialect_.throwError(x->text, dialect_.mostSevere(errors));
      } catch (...) {
        error = std::current_exception();
      }
    } else if (!x->collector.question().empty()) {
      out_of_sync_ = true;
      const std::string& q = x->collector.question();
      error = errorPtr(QuestionError(
          "the controller on " + link_.describe() + " asks \"" + q + "\" instead of showing its " +
              "prompt (" + dialect_.describePrompts() + "): answer it on the controller's own " +
              "terminal (robocal never answers a question for you), then try again",
          q));
    } else {
      lines = x->collector.lines();
    }
  }
  if (x->handler) x->handler(error, std::move(lines));
  if (!current_) startNext();
}

template <typename T>
T ValController::runSync(
    const std::function<void(std::function<void(std::exception_ptr, T)>)>& start,
    double timeout_s) {
  bool done = false;
  std::exception_ptr error;
  T result{};
  start([&](std::exception_ptr e, T r) {
    error = e;
    result = std::move(r);
    done = true;
  });
  // The operation has its own timers; this deadline only guards against a lost handler.
  if (!runIoUntil(
          io_, [&] { return done; }, deadlineAfter(timeout_s + 5))) {
    disconnect();
    throw TimeoutError("the controller driver on " + link_.describe() + " did not finish in time");
  }
  if (error) std::rethrow_exception(error);
  return result;
}

std::vector<std::string> ValController::command(const std::string& text, double timeout_s) {
  return runSync<std::vector<std::string>>(
      [&](ReplyHandler h) { asyncCommand(text, timeout_s, std::move(h)); }, timeout_s + 1);
}

void ValController::asyncWhere(WhereHandler handler) {
  asyncWhere(dialect_.config().where_timeout_s, std::move(handler));
}

void ValController::asyncWhere(double timeout_s, WhereHandler handler) {
  asyncCommand(
      dialect_.config().where_command, timeout_s,
      [this, handler = std::move(handler)](std::exception_ptr e, std::vector<std::string> lines) {
        if (e) return handler(e, {});
        WhereReply w;
        try {
          w = parseWhere(lines, dialect_.config());
        } catch (...) {
          return handler(std::current_exception(), {});
        }
        last_joints_ = w.joints_deg;
        handler(nullptr, w);
      });
}

WhereReply ValController::where() {
  return runSync<WhereReply>([&](WhereHandler h) { asyncWhere(std::move(h)); },
                             dialect_.config().where_timeout_s + 1);
}

void ValController::setSpeed(double percent) {
  if (!(percent > 0 && percent <= 100))
    throw DriverError("speed must be more than 0 and at most 100 percent, not " +
                      formatFixed(percent, 2));
  command(dialect_.speedCommand(percent), dialect_.config().command_timeout_s);
  speed_percent_ = percent;
}

double ValController::moveCommandTimeout(const Joints6& target) const {
  return pathCommandTimeout({target});
}

void ValController::abort() {
  poll_timer_.cancel();
  command(dialect_.config().abort_command, dialect_.config().abort_timeout_s);
}

void ValController::startMove(const Joints6& target) {
  for (double v : target)
    if (!std::isfinite(v)) throw DriverError("move target has a joint angle that is not a number");
  runSync<std::vector<std::string>>(
      [&](ReplyHandler h) {
        asyncCommand(dialect_.moveCommand(target), moveCommandTimeout(target),
                     dialect_.config().move_timeout_s, std::move(h));
      },
      moveCommandTimeout(target) + 1);
}

void ValController::pollMotion(std::shared_ptr<MotionMonitor> monitor, Joints6 target,
                               WhereHandler handler, ProgressHandler progress,
                               double where_timeout_s) {
  ++stats_.where_polls;
  std::weak_ptr<int> alive = alive_;
  const double retry_timeout_s = dialect_.config().where_timeout_s;
  asyncWhere(where_timeout_s, [this, alive, monitor, target, handler, progress, retry_timeout_s](
                                  std::exception_ptr e, WhereReply w) {
    if (e) {
      // A garbled or cut WHERE reply is asked again (where_retries in a row) before giving up,
      // after the line has been quiet: the rest of the bad reply (or a completion line) is
      // drained rather than read as the next reply.
      try {
        std::rethrow_exception(e);
      } catch (const ProtocolError&) {
        if (++monitor->unreadable <= dialect_.config().where_retries && !alive.expired()) {
          ++stats_.where_retries;
          out_of_sync_ = true;
          return pollMotion(monitor, target, handler, progress, retry_timeout_s);
        }
      } catch (...) {
      }
      return handler(e, {});
    }
    monitor->unreadable = 0;
    if (progress) progress(w);
    const auto state = monitor->update(w.joints_deg, Clock::now());
    if (state == MotionMonitor::State::kArrived) return handler(nullptr, w);
    if (state != MotionMonitor::State::kMoving)
      return handler(errorPtr(MotionError(monitor->explain(state, w.joints_deg))), w);
    if (alive.expired()) return;
    poll_timer_.expires_after(seconds(dialect_.config().poll_interval_s));
    poll_timer_.async_wait(
        [this, alive, monitor, target, handler, progress](const boost::system::error_code& ec) {
          if (alive.expired()) return;
          if (ec) return handler(errorPtr(MotionError("waiting for the motion was cancelled")), {});
          pollMotion(monitor, target, handler, progress, dialect_.config().where_timeout_s);
        });
  });
}

void ValController::asyncMoveJoints(const Joints6& target, WhereHandler handler,
                                    ProgressHandler progress) {
  for (double v : target)
    if (!std::isfinite(v)) {
      boost::asio::post(io_, [handler] {
        handler(errorPtr(DriverError("move target has a joint angle that is not a number")), {});
      });
      return;
    }
  asyncMotionCommand(dialect_.moveCommand(target), moveCommandTimeout(target), target,
                     std::move(handler), std::move(progress));
}

void ValController::asyncMotionCommand(const std::string& text, double timeout_s,
                                       const Joints6& target, WhereHandler handler,
                                       ProgressHandler progress) {
  const auto start = Clock::now();
  asyncCommand(
      text, timeout_s, dialect_.config().move_timeout_s,
      [this, target, handler, progress, start](std::exception_ptr e, std::vector<std::string>) {
        const ValConfig& c = dialect_.config();
        double first_where_s = c.where_timeout_s;
        if (e) {
          // Echoed, then no prompt in time: the controller may be busy with the move itself
          // (a synchronous DO MOVE). The motion monitor decides, from WHERE, not the prompt.
          try {
            std::rethrow_exception(e);
          } catch (const CommandTimeoutError& t) {
            if (!t.echoSeen()) return handler(e, {});
            ++stats_.move_timeouts_watched;
            first_where_s = std::max(c.where_timeout_s,
                                     c.motion_timeout_s - secondsSince(start) + c.where_timeout_s);
          } catch (...) {
            return handler(e, {});
          }
        }
        pollMotion(std::make_shared<MotionMonitor>(c, target, start), target, handler, progress,
                   first_where_s);
      });
}

WhereReply ValController::waitForMotion(const Joints6& target, const ProgressHandler& progress) {
  return runSync<WhereReply>(
      [&](WhereHandler h) {
        pollMotion(std::make_shared<MotionMonitor>(dialect_.config(), target, Clock::now()), target,
                   std::move(h), progress, dialect_.config().where_timeout_s);
      },
      dialect_.config().motion_timeout_s + dialect_.config().where_timeout_s + 1);
}

WhereReply ValController::moveJoints(const Joints6& target, const ProgressHandler& progress) {
  return runSync<WhereReply>(
      [&](WhereHandler h) { asyncMoveJoints(target, std::move(h), progress); },
      moveCommandTimeout(target) + dialect_.config().motion_timeout_s +
          2 * dialect_.config().where_timeout_s + 1);
}

}  // namespace robocal::drivers
