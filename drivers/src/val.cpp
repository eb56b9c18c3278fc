#include <robocal/drivers/val.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <thread>

namespace robocal::drivers {

namespace {
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
}  // namespace

ValController::ValController(boost::asio::io_context& io, ValConfig config)
    : io_(io), dialect_(std::move(config)), link_(io, dialect_.config().serial) {
  validate(dialect_.config());
}

void ValController::connect() {
  link_.open();
  out_of_sync_ = true;
  pending_errors_.clear();
  try {
    command("", dialect_.config().connect_timeout_s);
  } catch (const TimeoutError& e) {
    throw TimeoutError(std::string(e.what()) +
                       " (no prompt after waking the monitor with an empty line)");
  }
}

void ValController::reconnect(double within_s) {
  const auto deadline = deadlineAfter(within_s);
  std::string last = "not tried";
  while (true) {
    try {
      connect();
      return;
    } catch (const PortError& e) {
      last = e.what();
    } catch (const DisconnectedError& e) {
      last = e.what();
    } catch (const TimeoutError& e) {
      last = e.what();
    }
    link_.close();
    if (Clock::now() >= deadline)
      throw PortError("could not reconnect to the controller within " + formatFixed(within_s, 1) +
                      " s: " + last);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}

void ValController::disconnect() {
  link_.close();
}

void ValController::drainUnsolicited() {
  // Whatever arrived since the last reply: an E-stop message, or a late reply after a timeout.
  std::string bytes;
  const auto quiet = std::chrono::milliseconds(out_of_sync_ ? 80 : 0);
  while (link_.readSome(bytes, Clock::now() + quiet)) {
  }
  if (bytes.empty()) return;
  LineSplitter splitter;
  std::vector<std::string> lines;
  splitter.feed(bytes, lines);
  for (const auto& l : lines) {
    if (trim(l).empty()) continue;
    ++stats_.unsolicited_lines;
    if (auto msg = dialect_.errorMessage(trim(l))) pending_errors_.push_back(*msg);
  }
}

std::vector<std::string> ValController::command(const std::string& text, double timeout_s) {
  if (!link_.isOpen())
    throw DisconnectedError("the controller port " + link_.describe() + " is not open");
  drainUnsolicited();
  out_of_sync_ = false;
  ++stats_.commands;
  const auto deadline = deadlineAfter(timeout_s);
  ValReplyCollector reply(dialect_, text);
  link_.write(text + dialect_.config().send_line_ending, deadline);
  std::string chunk;
  while (!reply.complete()) {
    chunk.clear();
    if (!link_.readSome(chunk, deadline)) {
      ++stats_.timeouts;
      out_of_sync_ = true;
      std::string what = "no answer from the controller on " + link_.describe() + " to \"" + text +
                         "\" within " + formatFixed(timeout_s, 1) + " s";
      if (reply.raw().empty())
        what += ": is it powered on and at the monitor prompt '" + dialect_.config().prompt +
                "', the cable a null-modem one, and the baud rate right?";
      else if (!looksLikeText(reply.raw()))
        what += ": it sent bytes that are not text (" + escapeBytes(reply.raw().substr(0, 40)) +
                "): wrong baud rate or parity, or a garbling USB adapter";
      else
        what += ": it sent \"" + escapeBytes(reply.raw().substr(0, 120)) +
                "\" but no prompt: is the prompt configured right (val.prompt)?";
      throw TimeoutError(what);
    }
    reply.feed(chunk);
  }
  std::vector<std::string> errors = std::move(pending_errors_);
  pending_errors_.clear();
  errors.insert(errors.end(), reply.errors().begin(), reply.errors().end());
  if (!errors.empty()) {
    ++stats_.controller_errors;
    out_of_sync_ = true;  // an unsolicited error may have cut a reply short: drain before the next
    dialect_.throwError(text, errors.front());
  }
  return reply.lines();
}

WhereReply ValController::where() {
  const auto lines = command(dialect_.config().where_command, dialect_.config().where_timeout_s);
  return parseWhere(lines, dialect_.config());
}

void ValController::setSpeed(double percent) {
  if (!(percent > 0 && percent <= 100))
    throw DriverError("speed must be more than 0 and at most 100 percent, not " +
                      formatFixed(percent, 2));
  command(dialect_.speedCommand(percent), dialect_.config().command_timeout_s);
}

void ValController::abort() {
  command(dialect_.config().abort_command, dialect_.config().abort_timeout_s);
}

void ValController::startMove(const Joints6& target) {
  for (double v : target)
    if (!std::isfinite(v)) throw DriverError("move target has a joint angle that is not a number");
  command(dialect_.moveCommand(target), dialect_.config().move_timeout_s);
}

WhereReply ValController::waitForMotion(const Joints6& target,
                                        const std::function<void(const WhereReply&)>& progress) {
  const ValConfig& c = dialect_.config();
  const auto start = Clock::now();
  const auto deadline = deadlineAfter(c.motion_timeout_s);
  std::optional<Joints6> previous;
  int still = 0;
  auto moving_since = Clock::now();
  while (true) {
    ++stats_.where_polls;
    const WhereReply w = where();
    if (progress) progress(w);
    const auto now = Clock::now();
    const double off = maxAbsDiff(w.joints_deg, target);
    if (previous && maxAbsDiff(w.joints_deg, *previous) <= c.still_tol_deg) {
      ++still;
    } else {
      still = 0;
      moving_since = now;
    }
    previous = w.joints_deg;
    if (still >= c.still_polls) {
      if (off <= c.at_target_tol_deg) return w;
      if (std::chrono::duration<double>(now - moving_since).count() >= c.stopped_short_s)
        throw MotionError("the arm stopped " + formatFixed(off, 3) +
                          " deg short of the target and stayed still for " +
                          formatFixed(c.stopped_short_s, 1) +
                          " s (E-stop, a collision, or a move the controller dropped): at " +
                          describeJoints(w.joints_deg) + ", target " + describeJoints(target));
    }
    if (now >= deadline)
      throw MotionError("the arm did not reach the target within " +
                        formatFixed(c.motion_timeout_s, 1) + " s: at " +
                        describeJoints(w.joints_deg) + ", target " + describeJoints(target) + " (" +
                        formatFixed(off, 3) + " deg off)");
    (void)start;
    std::this_thread::sleep_for(std::chrono::duration<double>(c.poll_interval_s));
  }
}

WhereReply ValController::moveJoints(const Joints6& target,
                                     const std::function<void(const WhereReply&)>& progress) {
  startMove(target);
  return waitForMotion(target, progress);
}

}  // namespace robocal::drivers
