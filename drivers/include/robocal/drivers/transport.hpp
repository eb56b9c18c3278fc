// The byte-stream seam: one serial port as a boost::asio::posix::stream_descriptor, opened with
// libserialport (real ports, found by path or by USB serial number / description; settings from
// the config; exclusive) or with termios (pseudo-terminals, which libserialport cannot open).
// The I/O is the same Asio code either way. The daemon uses stream() asynchronously in its event
// loop; tests and the command line use the synchronous helpers, which run the io_context in the
// calling thread until the operation completes or its deadline passes.
#pragma once

#include <termios.h>

#include <robocal/drivers/config.hpp>
#include <robocal/drivers/errors.hpp>

#include <boost/asio/io_context.hpp>
#include <boost/asio/posix/stream_descriptor.hpp>

#include <array>
#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace robocal::drivers {

using Clock = std::chrono::steady_clock;
Clock::time_point deadlineAfter(double seconds);

// One serial port as libserialport enumerates it.
struct PortInfo {
  std::string path;
  std::string description;
  std::string transport;  // usb | native | bluetooth
  std::string usb_manufacturer, usb_product, usb_serial;
  int usb_vid = -1, usb_pid = -1;
  int usb_bus = -1, usb_address = -1;
};
std::vector<PortInfo> listSerialPorts();

// True for /dev/pts/N (and symlinks to it): a pseudo-terminal, opened with termios.
bool isPseudoTerminal(const std::string& path);
// The device path the config names: `path` itself, or the enumerated port whose USB serial
// number equals usb_serial and/or whose description, product or manufacturer contains
// usb_description. PortError listing the ports present when nothing (or more than one) matches.
std::string resolvePortPath(const SerialConfig& config);
// The matching part of resolvePortPath, on a given list of ports.
std::string matchPort(const std::vector<PortInfo>& ports, const SerialConfig& config);

// Runs `io` in the calling thread until done() or the deadline; returns done().
bool runIoUntil(boost::asio::io_context& io, const std::function<bool()>& done,
                Clock::time_point deadline);

class SerialLink {
 public:
  SerialLink(boost::asio::io_context& io, SerialConfig config);
  ~SerialLink();
  SerialLink(const SerialLink&) = delete;
  SerialLink& operator=(const SerialLink&) = delete;

  // Opens (or re-opens) the port; PortError in technician words when it cannot.
  void open();
  void close();
  bool isOpen() const { return stream_.is_open(); }
  const SerialConfig& config() const { return config_; }
  // The resolved device path and how it was opened ("termios" or "libserialport").
  const std::string& path() const { return path_; }
  const std::string& opener() const { return opener_; }
  std::string describe() const;

  boost::asio::io_context& context() { return io_; }
  boost::asio::posix::stream_descriptor& stream() { return stream_; }

  // Synchronous helpers. TimeoutError at the deadline, DisconnectedError when the port goes away
  // (the link is then closed; open() again to reconnect).
  void write(std::string_view bytes, Clock::time_point deadline);
  // Appends at least one received byte to `out`; false when nothing came before the deadline.
  bool readSome(std::string& out, Clock::time_point deadline);
  // Discards input already received (by the kernel) and not yet read.
  void discardInput();

  // Called by asynchronous users when a read or write failed: closes the link and returns the
  // DisconnectedError that describes it.
  DisconnectedError disconnected(const std::string& why);

  // The receive loop of the drivers, on the io_context. From receive() on, every chunk of bytes
  // that arrives goes to on_bytes, the next read armed before it is called (so a handler that
  // throws does not stop the loop); a read error ends the loop and goes to on_error with its
  // reason. close() ends it too and orphans the pending read: no handler runs after close().
  void receive(std::function<void(std::string_view)> on_bytes,
               std::function<void(const std::string&)> on_error);
  // Restarts the loop when the port is open and no read is pending (a no-op otherwise).
  void resumeReceiving();

 private:
  void openTermios();
  void openLibserialport();
  // Runs the io_context until `done` or the deadline; on time-out cancels the pending
  // operation, waits for its handler, and returns false.
  bool finishOrCancel(const bool& done, Clock::time_point deadline);

  boost::asio::io_context& io_;
  SerialConfig config_;
  boost::asio::posix::stream_descriptor stream_;
  std::string path_, opener_;
  void* sp_port_ = nullptr;  // struct sp_port*, kept open while libserialport owns the port
  int sp_fd_ = -1;
  std::array<char, 4096> buffer_{};
  // The receive loop: its handlers, buffer, and the token its pending read holds a weak_ptr of.
  std::function<void(std::string_view)> on_bytes_;
  std::function<void(const std::string&)> on_error_;
  std::array<char, 1024> receive_buffer_{};
  std::shared_ptr<int> receive_alive_;
  bool reading_ = false;
};

// The drivers' reconnect(within_s): calls connect() until it succeeds, retrying every 100 ms
// for up to within_s when it fails with PortError, DisconnectedError or TimeoutError (after
// calling after_failure, when given). Then PortError "could not reconnect to <device> within
// <within_s> s: <the last failure>". Other errors pass through at once.
void reconnectWithin(double within_s, const std::string& device,
                     const std::function<void()>& connect,
                     const std::function<void()>& after_failure = {});

// The termios speed constant for a baud rate, or 0 when termios has none for it.
speed_t termiosSpeed(int baud);

}  // namespace robocal::drivers
