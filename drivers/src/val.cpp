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

double maxAbsDiff(const Joints6& a, const Joints6& b) {
  double m = 0;
  for (int i = 0; i < 6; ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
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
  if (previous_ && maxAbsDiff(joints, *previous_) <= config_.still_tol_deg) {
    ++still_;
  } else {
    still_ = 0;
    moving_since_ = now;
  }
  previous_ = joints;
  if (still_ >= config_.still_polls) {
    if (maxAbsDiff(joints, target_) <= config_.at_target_tol_deg) return State::kArrived;
    if (now - moving_since_ >= seconds(config_.stopped_short_s)) return State::kStoppedShort;
  }
  if (now >= deadline_) return State::kTimedOut;
  return State::kMoving;
}

std::string MotionMonitor::explain(State state, const Joints6& joints) const {
  const std::string where = ": at " + describeJoints(joints) + ", target " +
                            describeJoints(target_) + " (" +
                            formatFixed(maxAbsDiff(joints, target_), 3) + " deg off)";
  if (state == State::kStoppedShort)
    return "the arm stopped short of the target and stayed still for " +
           formatFixed(config_.stopped_short_s, 1) +
           " s (E-stop, a collision, or a move the controller dropped)" + where;
  return "the arm did not reach the target within " + formatFixed(config_.motion_timeout_s, 1) +
         " s" + where;
}

// ------------------------------------------------------------------------------- ValController

struct ValController::Exchange {
  Exchange(const ValDialect& dialect, std::string command, double timeout, ReplyHandler h)
      : text(std::move(command)),
        timeout_s(timeout),
        collector(dialect, text),
        handler(std::move(h)) {}
  std::string text;
  double timeout_s;
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
      poll_timer_(io) {
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
  if (!current_->collector.feed(bytes)) return;
  // What followed the reply in the same read was printed after it: an error there (an E-stop)
  // is reported with this reply rather than lost.
  unsolicited(current_->collector.rest());
  finish(nullptr);
}

void ValController::unsolicited(std::string_view bytes) {
  std::vector<std::string> lines;
  unsolicited_splitter_.feed(bytes, lines);
  for (const auto& l : lines) {
    if (trim(l).empty()) continue;
    ++stats_.unsolicited_lines;
    if (auto msg = dialect_.errorMessage(trim(l))) {
      pending_errors_.push_back(*msg);
      if (unsolicited_callback_) unsolicited_callback_(*msg);
    }
  }
}

void ValController::asyncCommand(const std::string& text, double timeout_s, ReplyHandler handler) {
  auto x = std::make_unique<Exchange>(dialect_, text, timeout_s, std::move(handler));
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
  timer_.expires_at(current_->deadline);
  timer_.async_wait([this, alive, id](const boost::system::error_code& ec) {
    if (ec || alive.expired() || !current_ || exchange_id_ != id) return;
    ++stats_.timeouts;
    out_of_sync_ = true;
    const ValReplyCollector& reply = current_->collector;
    const std::string& text = current_->text;
    std::string what = "no answer from the controller on " + link_.describe() + " to \"" + text +
                       "\" within " + formatFixed(current_->timeout_s, 1) + " s";
    if (reply.raw().empty())
      what += ": is it powered on and at the monitor prompt '" + dialect_.config().prompt +
              "', the cable a null-modem one, and the baud rate right?";
    else if (!looksLikeText(reply.raw()))
      what += ": it sent bytes that are not text (" + escapeBytes(reply.raw().substr(0, 40)) +
              "): wrong baud rate or parity, or a garbling USB adapter";
    else
      what += ": it sent \"" + escapeBytes(reply.raw().substr(0, 120)) +
              "\" but no prompt: is the prompt configured right (val.prompt)?";
    finish(errorPtr(TimeoutError(what)));
  });
}

void ValController::finish(std::exception_ptr error) {
  timer_.cancel();
  std::unique_ptr<Exchange> x = std::move(current_);
  std::vector<std::string> lines;
  if (!error) {
    std::vector<std::string> errors = std::move(pending_errors_);
    pending_errors_.clear();
    errors.insert(errors.end(), x->collector.errors().begin(), x->collector.errors().end());
    if (!errors.empty()) {
      ++stats_.controller_errors;
      out_of_sync_ = true;  // an unsolicited error may have cut a reply short: drain first
      try {
        dialect_.throwError(x->text, errors.front());
      } catch (...) {
        error = std::current_exception();
      }
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
  asyncCommand(
      dialect_.config().where_command, dialect_.config().where_timeout_s,
      [this, handler = std::move(handler)](std::exception_ptr e, std::vector<std::string> lines) {
        if (e) return handler(e, {});
        WhereReply w;
        try {
          w = parseWhere(lines, dialect_.config());
        } catch (...) {
          return handler(std::current_exception(), {});
        }
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
}

void ValController::abort() {
  poll_timer_.cancel();
  command(dialect_.config().abort_command, dialect_.config().abort_timeout_s);
}

void ValController::startMove(const Joints6& target) {
  for (double v : target)
    if (!std::isfinite(v)) throw DriverError("move target has a joint angle that is not a number");
  command(dialect_.moveCommand(target), dialect_.config().move_timeout_s);
}

void ValController::pollMotion(std::shared_ptr<MotionMonitor> monitor, Joints6 target,
                               WhereHandler handler, ProgressHandler progress) {
  ++stats_.where_polls;
  std::weak_ptr<int> alive = alive_;
  asyncWhere([this, alive, monitor, target, handler, progress](std::exception_ptr e, WhereReply w) {
    if (e) {
      // A garbled or cut WHERE reply is asked again (where_retries in a row) before giving up.
      try {
        std::rethrow_exception(e);
      } catch (const ProtocolError&) {
        if (++monitor->unreadable <= dialect_.config().where_retries && !alive.expired()) {
          ++stats_.where_retries;
          return pollMotion(monitor, target, handler, progress);
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
          pollMotion(monitor, target, handler, progress);
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
  asyncCommand(dialect_.moveCommand(target), dialect_.config().move_timeout_s,
               [this, target, handler, progress](std::exception_ptr e, std::vector<std::string>) {
                 if (e) return handler(e, {});
                 pollMotion(
                     std::make_shared<MotionMonitor>(dialect_.config(), target, Clock::now()),
                     target, handler, progress);
               });
}

WhereReply ValController::waitForMotion(const Joints6& target, const ProgressHandler& progress) {
  return runSync<WhereReply>(
      [&](WhereHandler h) {
        pollMotion(std::make_shared<MotionMonitor>(dialect_.config(), target, Clock::now()), target,
                   std::move(h), progress);
      },
      dialect_.config().motion_timeout_s + dialect_.config().where_timeout_s + 1);
}

WhereReply ValController::moveJoints(const Joints6& target, const ProgressHandler& progress) {
  return runSync<WhereReply>(
      [&](WhereHandler h) { asyncMoveJoints(target, std::move(h), progress); },
      dialect_.config().move_timeout_s + dialect_.config().motion_timeout_s +
          dialect_.config().where_timeout_s + 1);
}

}  // namespace robocal::drivers
