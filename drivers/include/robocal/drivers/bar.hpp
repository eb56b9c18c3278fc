// The LVDT ball-bar reader: polled or streamed ASCII lines, parsed by the configured regular
// expression. Every reading carries a monotonic timestamp; garbage and partial lines are counted
// and skipped; no valid reading for stale_after_s is a StaleReadingError.
//
// The receive loop is asynchronous on the io_context (the daemon gets every line through
// onLine()); read() is the synchronous call for tests and the command line, which runs the
// io_context in the calling thread.
#pragma once

#include <robocal/drivers/config.hpp>
#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/protocol.hpp>
#include <robocal/drivers/transport.hpp>

#include <boost/asio/io_context.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace robocal::drivers {

struct BarReading {
  BarLineKind kind = BarLineKind::kReading;  // never kGarbage
  double value_mm = 0;                       // kReading only: the LVDT value in mm
  Clock::time_point time{};                  // when the line ended (steady clock)
  std::uint64_t sequence = 0;                // 1, 2, ... per reader
  std::string line;                          // as received
};

struct BarStats {
  long readings = 0;    // valid values
  long over_range = 0;  // over or under range lines (and values past range_mm)
  long no_probe = 0;
  long device_errors = 0;
  long garbage_lines = 0;  // lines that match nothing, or hold non-text bytes
  long partial_lines = 0;  // fragments without a line ending, discarded
  long timeouts = 0;       // polls without an answer in poll_timeout_s
  long disconnects = 0;
  std::string last_garbage;       // the last unrecognised line, for diagnostics
  std::string last_text_garbage;  // the last unrecognised line that was readable text
};

class BarReader {
 public:
  BarReader(boost::asio::io_context& io, BarConfig config);
  ~BarReader();
  BarReader(const BarReader&) = delete;
  BarReader& operator=(const BarReader&) = delete;

  // Opens the port and starts the receive loop.
  void connect();
  // Re-opens the port retrying for up to within_s (PortError with the last reason).
  void reconnect(double within_s);
  void disconnect();
  bool isConnected() const { return link_.isOpen() && !disconnected_; }

  // The next reading or status line received after this call (polled: after sending the poll
  // command, again every poll_timeout_s). StaleReadingError when none comes in stale_after_s,
  // DisconnectedError when the port goes away.
  BarReading read();
  // read(), requiring a value: BarStatusError for over range, no probe or a device error.
  double readValueMm();

  std::optional<BarReading> latest() const { return latest_; }
  // No valid reading within stale_after_s before `now`.
  bool isStale(Clock::time_point now = Clock::now()) const;
  const BarStats& stats() const { return stats_; }
  const BarDialect& dialect() const { return dialect_; }
  SerialLink& link() { return link_; }
  // Called from the io_context for every reading or status line (not for garbage).
  void onLine(std::function<void(const BarReading&)> callback) { callback_ = std::move(callback); }

 private:
  void received(std::string_view bytes);
  void handleLine(const std::string& line);
  void drainBacklog();
  void dropPartial();

  boost::asio::io_context& io_;
  BarDialect dialect_;
  SerialLink link_;
  LineSplitter splitter_;
  bool disconnected_ = false;
  std::string disconnect_reason_;
  std::optional<BarReading> latest_, latest_valid_;
  std::uint64_t sequence_ = 0;
  BarStats stats_;
  std::function<void(const BarReading&)> callback_;
};

}  // namespace robocal::drivers
