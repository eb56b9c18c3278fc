#include <robocal/drivers/bar.hpp>

#include <thread>

namespace robocal::drivers {

namespace {
constexpr std::size_t kMaxLineBytes = 256;  // longer without a line ending: a partial line
}

BarReader::BarReader(boost::asio::io_context& io, BarConfig config)
    : io_(io), dialect_(std::move(config)), link_(io, dialect_.config().serial) {
  validate(dialect_.config());
}

BarReader::~BarReader() {
  link_.close();  // orphans the pending read: no handler runs after this
}

void BarReader::connect() {
  link_.open();  // closes the previous connection first, orphaning its handlers
  disconnected_ = false;
  disconnect_reason_.clear();
  splitter_.clear();
  link_.receive([this](std::string_view bytes) { received(bytes); },
                [this](const std::string& why) {
                  dropPartial();
                  disconnected_ = true;
                  ++stats_.disconnects;
                  disconnect_reason_ = link_.disconnected(why).what();
                });
}

void BarReader::reconnect(double within_s) {
  reconnectWithin(within_s, "the ball-bar reader", [this] { connect(); });
}

void BarReader::disconnect() {
  link_.close();
}

void BarReader::received(std::string_view bytes) {
  std::vector<std::string> lines;
  splitter_.feed(bytes, lines);
  for (const auto& l : lines) handleLine(l);
  if (splitter_.pending().size() > kMaxLineBytes) dropPartial();
}

void BarReader::dropPartial() {
  if (splitter_.pending().empty()) return;
  ++stats_.partial_lines;
  splitter_.takePending();
}

void BarReader::handleLine(const std::string& line) {
  if (trim(line).empty()) return;
  const BarLine parsed = dialect_.parse(line);
  switch (parsed.kind) {
    case BarLineKind::kGarbage:
      ++stats_.garbage_lines;
      stats_.last_garbage = line.substr(0, 80);
      if (isPrintableText(line)) stats_.last_text_garbage = stats_.last_garbage;
      return;
    case BarLineKind::kReading:
      ++stats_.readings;
      break;
    case BarLineKind::kOverRange:
      ++stats_.over_range;
      break;
    case BarLineKind::kNoProbe:
      ++stats_.no_probe;
      break;
    case BarLineKind::kDeviceError:
      ++stats_.device_errors;
      break;
  }
  BarReading r;
  r.kind = parsed.kind;
  r.value_mm = parsed.value_mm;
  r.time = Clock::now();
  r.sequence = ++sequence_;
  r.line = line;
  latest_ = r;
  if (r.kind == BarLineKind::kReading) latest_valid_ = r;
  if (callback_) callback_(r);
}

void BarReader::drainBacklog() {
  // Lines that waited in the kernel while nobody ran the io_context are old: process them now so
  // that read() returns only what arrives after it was called.
  if (io_.stopped()) io_.restart();
  while (io_.poll() > 0) {
  }
}

bool BarReader::isStale(Clock::time_point now) const {
  return !latest_valid_ || std::chrono::duration<double>(now - latest_valid_->time).count() >
                               dialect_.config().stale_after_s;
}

BarReading BarReader::read() {
  const BarConfig& c = dialect_.config();
  const auto not_connected = [&] {
    return DisconnectedError(disconnect_reason_.empty()
                                 ? "the ball-bar reader port " + link_.describe() + " is not open"
                                 : disconnect_reason_);
  };
  if (!isConnected()) throw not_connected();
  drainBacklog();
  if (!isConnected()) throw not_connected();
  const auto stale_deadline = deadlineAfter(c.stale_after_s);
  const bool polled = c.mode == "polled";
  const std::uint64_t start = sequence_;
  const long garbage_before = stats_.garbage_lines + stats_.partial_lines;
  while (true) {
    auto attempt_deadline = stale_deadline;
    if (polled) {
      dropPartial();
      link_.write(dialect_.pollCommandBytes(), deadlineAfter(c.poll_timeout_s));
      attempt_deadline = std::min(stale_deadline, deadlineAfter(c.poll_timeout_s));
    }
    link_.resumeReceiving();  // a no-op while the receive loop runs
    if (!runIoUntil(
            io_, [&] { return sequence_ != start || disconnected_; }, attempt_deadline) &&
        Clock::now() < attempt_deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));  // no work: do not spin
    if (sequence_ != start) return *latest_;
    if (disconnected_) throw not_connected();
    ++stats_.timeouts;
    if (Clock::now() >= stale_deadline) {
      const long garbage = stats_.garbage_lines + stats_.partial_lines - garbage_before;
      std::string what = "no reading from the ball-bar reader on " + link_.describe() + " for " +
                         formatFixed(c.stale_after_s, 1) + " s";
      if (garbage > 0)
        what += ": " + std::to_string(garbage) +
                " line(s) came that match no configured pattern (wrong baud rate, or "
                "bar.value_regex does not fit the reader's format?)";
      else if (polled)
        what += ": it does not answer the poll command \"" + escapeBytes(c.poll_command) +
                "\" (powered on? cable? baud rate? bar.mode should be streamed?)";
      else
        what += ": the stream stopped (powered on? cable? bar.mode should be polled?)";
      throw StaleReadingError(what);
    }
  }
}

double BarReader::readValueMm() {
  const BarReading r = read();
  switch (r.kind) {
    case BarLineKind::kReading:
      return r.value_mm;
    case BarLineKind::kOverRange:
      throw BarStatusError("the ball-bar is over range (\"" + r.line +
                           "\"): the bar is stretched or compressed past the LVDT's travel");
    case BarLineKind::kNoProbe:
      throw BarStatusError("the ball-bar reader reports no probe (\"" + r.line +
                           "\"): is the LVDT cable plugged into the reader?");
    default:
      throw BarStatusError("the ball-bar reader reports an error: \"" + r.line + "\"");
  }
}

}  // namespace robocal::drivers
