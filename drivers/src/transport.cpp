#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/protocol.hpp>
#include <robocal/drivers/transport.hpp>

#include <libserialport.h>
#include <boost/asio/read.hpp>
#include <boost/asio/write.hpp>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <thread>

namespace robocal::drivers {

Clock::time_point deadlineAfter(double seconds) {
  return Clock::now() +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

bool runIoUntil(boost::asio::io_context& io, const std::function<bool()>& done,
                Clock::time_point deadline) {
  // Whatever is ready runs even when the deadline has passed (a zero-time drain).
  if (io.stopped()) io.restart();
  io.poll();
  while (!done()) {
    if (Clock::now() >= deadline) return false;
    if (io.stopped()) io.restart();
    // No work left at all: nothing can change the condition, so do not wait for the deadline.
    if (io.run_one_until(deadline) == 0 && io.stopped() && !done()) return false;
  }
  return true;
}

namespace {

std::string lowerCase(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string str(const char* s) {
  return s ? s : "";
}

std::string spError() {
  char* msg = sp_last_error_message();
  std::string out = str(msg);
  sp_free_error_message(msg);
  return out;
}

// What a technician should check for an errno from opening a port.
std::string openAdvice(int err, const std::string& path) {
  switch (err) {
    case ENOENT:
    case ENODEV:
    case ENXIO:
      return "no such port " + path +
             ": is the USB-serial adapter plugged in and the path right? (`robocal ports` lists "
             "the ports this machine has)";
    case EACCES:
    case EPERM:
      return "no permission to open " + path +
             ": add this user to the 'dialout' group (then log in again) or run as the service "
             "user";
    case EBUSY:
    case EWOULDBLOCK:
      return path +
             " is in use by another program (a terminal program, another robocal, "
             "ModemManager?): close it first";
    default:
      return "cannot open " + path + ": " + std::strerror(err);
  }
}

}  // namespace

speed_t termiosSpeed(int baud) {
  switch (baud) {
    case 300:
      return B300;
    case 600:
      return B600;
    case 1200:
      return B1200;
    case 2400:
      return B2400;
    case 4800:
      return B4800;
    case 9600:
      return B9600;
    case 19200:
      return B19200;
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    case 115200:
      return B115200;
    case 230400:
      return B230400;
    default:
      return 0;
  }
}

std::vector<PortInfo> listSerialPorts() {
  sp_port** list = nullptr;
  if (sp_list_ports(&list) != SP_OK) throw PortError("cannot list the serial ports: " + spError());
  std::vector<PortInfo> out;
  for (int i = 0; list[i]; ++i) {
    sp_port* p = list[i];
    PortInfo info;
    info.path = str(sp_get_port_name(p));
    info.description = str(sp_get_port_description(p));
    switch (sp_get_port_transport(p)) {
      case SP_TRANSPORT_USB: {
        info.transport = "usb";
        info.usb_manufacturer = str(sp_get_port_usb_manufacturer(p));
        info.usb_product = str(sp_get_port_usb_product(p));
        info.usb_serial = str(sp_get_port_usb_serial(p));
        sp_get_port_usb_vid_pid(p, &info.usb_vid, &info.usb_pid);
        sp_get_port_usb_bus_address(p, &info.usb_bus, &info.usb_address);
        break;
      }
      case SP_TRANSPORT_BLUETOOTH:
        info.transport = "bluetooth";
        break;
      default:
        info.transport = "native";
        break;
    }
    out.push_back(std::move(info));
  }
  sp_free_port_list(list);
  return out;
}

bool isPseudoTerminal(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISCHR(st.st_mode)) return false;
  const unsigned m = major(st.st_rdev);
  return m >= 136 && m <= 143;  // Unix98 pty slaves (/dev/pts/N)
}

std::string resolvePortPath(const SerialConfig& config) {
  if (!config.path.empty()) return config.path;
  if (config.usb_serial.empty() && config.usb_description.empty())
    throw PortError(
        "no port configured: set serial.path, serial.usb_serial or "
        "serial.usb_description");
  return matchPort(listSerialPorts(), config);
}

std::string matchPort(const std::vector<PortInfo>& ports, const SerialConfig& config) {
  std::vector<PortInfo> matches;
  for (const auto& p : ports) {
    if (!config.usb_serial.empty() && p.usb_serial != config.usb_serial) continue;
    if (!config.usb_description.empty()) {
      const std::string want = lowerCase(config.usb_description);
      const std::string hay =
          lowerCase(p.description + " | " + p.usb_product + " | " + p.usb_manufacturer);
      if (hay.find(want) == std::string::npos) continue;
    }
    matches.push_back(p);
  }
  std::string what = "USB serial \"" + config.usb_serial + "\"";
  if (!config.usb_description.empty())
    what += (config.usb_serial.empty() ? std::string("") : " and ") + "description containing \"" +
            config.usb_description + "\"";
  if (config.usb_serial.empty()) what = "description containing \"" + config.usb_description + "\"";
  if (matches.size() == 1) return matches[0].path;
  std::string present;
  for (const auto& p : ports)
    present += "\n  " + p.path + "  " + p.description +
               (p.usb_serial.empty() ? "" : "  serial " + p.usb_serial);
  if (present.empty()) present = " none";
  if (matches.empty())
    throw PortError("no serial port with " + what +
                    ": is the adapter plugged in? Ports present:" + present);
  throw PortError("more than one serial port with " + what +
                  ": name the adapter more precisely (usb_serial). Ports present:" + present);
}

SerialLink::SerialLink(boost::asio::io_context& io, SerialConfig config)
    : io_(io), config_(std::move(config)), stream_(io) {}

SerialLink::~SerialLink() {
  close();
}

std::string SerialLink::describe() const {
  std::string d = path_.empty()
                      ? (config_.path.empty() ? std::string("(unresolved port)") : config_.path)
                      : path_;
  if (!config_.path.empty() && path_ != config_.path && !path_.empty())
    d = config_.path + " (" + path_ + ")";
  return d;
}

void SerialLink::open() {
  close();
  const std::string resolved = resolvePortPath(config_);
  path_ = resolved;
  std::string use = config_.opener;
  if (use == "auto") {
    struct stat st {};
    if (::stat(resolved.c_str(), &st) != 0) throw PortError(openAdvice(errno, resolved));
    use = isPseudoTerminal(resolved) ? "termios" : "libserialport";
  }
  if (use == "termios")
    openTermios();
  else
    openLibserialport();
  opener_ = use;
}

void SerialLink::openTermios() {
  const int fd = ::open(path_.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw PortError(openAdvice(errno, path_));
  const auto fail = [&](const std::string& msg) {
    ::close(fd);
    throw PortError(msg);
  };
  if (!::isatty(fd)) fail(path_ + " is not a serial port or terminal");
  if (config_.exclusive && ::flock(fd, LOCK_EX | LOCK_NB) != 0) fail(openAdvice(EBUSY, path_));
  termios t{};
  if (::tcgetattr(fd, &t) != 0)
    fail("cannot read the settings of " + path_ + ": " + std::strerror(errno));
  ::cfmakeraw(&t);
  const speed_t speed = termiosSpeed(config_.baud);
  if (speed == 0) fail("baud " + std::to_string(config_.baud) + " is not supported on " + path_);
  ::cfsetispeed(&t, speed);
  ::cfsetospeed(&t, speed);
  t.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | PARODD | CSTOPB | CRTSCTS);
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cflag |= config_.data_bits == 5   ? CS5
               : config_.data_bits == 6 ? CS6
               : config_.data_bits == 7 ? CS7
                                        : CS8;
  if (config_.parity == "odd") t.c_cflag |= PARENB | PARODD;
  if (config_.parity == "even") t.c_cflag |= PARENB;
  if (config_.stop_bits == 2) t.c_cflag |= CSTOPB;
  if (config_.flow_control == "rtscts") t.c_cflag |= CRTSCTS;
  if (config_.flow_control == "xonxoff") t.c_iflag |= IXON | IXOFF;
  t.c_cc[VMIN] = 1;
  t.c_cc[VTIME] = 0;
  if (::tcsetattr(fd, TCSANOW, &t) != 0)
    fail("cannot apply the settings to " + path_ + ": " + std::strerror(errno));
  ::tcflush(fd, TCIOFLUSH);
  stream_.assign(fd);
}

void SerialLink::openLibserialport() {
  sp_port* port = nullptr;
  if (sp_get_port_by_name(path_.c_str(), &port) != SP_OK) {
    struct stat st {};
    if (::stat(path_.c_str(), &st) != 0) throw PortError(openAdvice(errno, path_));
    throw PortError(path_ + " is not a serial port libserialport knows (" + spError() +
                    "); for a pseudo-terminal set serial.opener to \"termios\"");
  }
  const auto fail = [&](const std::string& msg) {
    sp_close(port);
    sp_free_port(port);
    throw PortError(msg);
  };
  if (sp_open(port, SP_MODE_READ_WRITE) != SP_OK) {
    const int err = errno;
    sp_free_port(port);
    throw PortError(openAdvice(err, path_) + " (" + spError() + ")");
  }
  sp_parity parity = SP_PARITY_NONE;
  if (config_.parity == "odd") parity = SP_PARITY_ODD;
  if (config_.parity == "even") parity = SP_PARITY_EVEN;
  if (config_.parity == "mark") parity = SP_PARITY_MARK;
  if (config_.parity == "space") parity = SP_PARITY_SPACE;
  sp_flowcontrol flow = SP_FLOWCONTROL_NONE;
  if (config_.flow_control == "xonxoff") flow = SP_FLOWCONTROL_XONXOFF;
  if (config_.flow_control == "rtscts") flow = SP_FLOWCONTROL_RTSCTS;
  if (sp_set_baudrate(port, config_.baud) != SP_OK ||
      sp_set_bits(port, config_.data_bits) != SP_OK || sp_set_parity(port, parity) != SP_OK ||
      sp_set_stopbits(port, config_.stop_bits) != SP_OK || sp_set_flowcontrol(port, flow) != SP_OK)
    fail("cannot apply baud " + std::to_string(config_.baud) + ", " +
         std::to_string(config_.data_bits) + " bits, parity " + config_.parity + ", " +
         std::to_string(config_.stop_bits) + " stop bit(s) to " + path_ + ": " + spError());
  int fd = -1;
  if (sp_get_port_handle(port, &fd) != SP_OK || fd < 0) fail("no file handle for " + path_);
  if (config_.exclusive) {
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) fail(openAdvice(EBUSY, path_));
#ifdef TIOCEXCL
    ::ioctl(fd, TIOCEXCL);
#endif
  }
  sp_flush(port, SP_BUF_BOTH);
  // Asio owns a duplicate of the descriptor; libserialport keeps the original until close().
  const int dup_fd = ::fcntl(fd, F_DUPFD_CLOEXEC, 0);
  if (dup_fd < 0) fail("cannot duplicate the handle of " + path_ + ": " + std::strerror(errno));
  sp_port_ = port;
  sp_fd_ = fd;
  stream_.assign(dup_fd);
}

void SerialLink::close() {
  receive_alive_.reset();  // orphans the pending read of the receive loop
  reading_ = false;
  boost::system::error_code ec;
  if (stream_.is_open()) {
    stream_.cancel(ec);
    stream_.close(ec);
  }
  if (sp_port_) {
    auto* port = static_cast<sp_port*>(sp_port_);
#ifdef TIOCNXCL
    if (sp_fd_ >= 0 && config_.exclusive) ::ioctl(sp_fd_, TIOCNXCL);
#endif
    sp_close(port);
    sp_free_port(port);
    sp_port_ = nullptr;
    sp_fd_ = -1;
  }
}

DisconnectedError SerialLink::disconnected(const std::string& why) {
  close();
  return DisconnectedError("lost the connection to " + describe() + " (" + why +
                           "): cable or USB adapter unplugged, or the device powered off");
}

void SerialLink::receive(std::function<void(std::string_view)> on_bytes,
                         std::function<void(const std::string&)> on_error) {
  on_bytes_ = std::move(on_bytes);
  on_error_ = std::move(on_error);
  receive_alive_ = std::make_shared<int>(0);
  reading_ = false;
  resumeReceiving();
}

void SerialLink::resumeReceiving() {
  if (reading_ || !isOpen() || !receive_alive_) return;
  reading_ = true;
  std::weak_ptr<int> alive = receive_alive_;
  stream_.async_read_some(boost::asio::buffer(receive_buffer_),
                          [this, alive](const boost::system::error_code& ec, std::size_t n) {
                            if (alive.expired()) return;  // closed, or the link is gone
                            reading_ = false;
                            if (ec == boost::asio::error::operation_aborted) return;
                            if (ec) {
                              if (on_error_) on_error_(ec.message());
                              return;
                            }
                            const std::string bytes(receive_buffer_.data(), n);
                            resumeReceiving();
                            if (on_bytes_) on_bytes_(bytes);
                          });
}

void reconnectWithin(double within_s, const std::string& device,
                     const std::function<void()>& connect,
                     const std::function<void()>& after_failure) {
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
    if (after_failure) after_failure();
    if (Clock::now() >= deadline)
      throw PortError("could not reconnect to " + device + " within " + formatFixed(within_s, 1) +
                      " s: " + last);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}

void SerialLink::write(std::string_view bytes, Clock::time_point deadline) {
  if (!isOpen()) throw DisconnectedError(describe() + " is not open");
  bool done = false;
  boost::system::error_code result;
  boost::asio::async_write(stream_, boost::asio::buffer(bytes.data(), bytes.size()),
                           [&](const boost::system::error_code& ec, std::size_t) {
                             result = ec;
                             done = true;
                           });
  if (!finishOrCancel(done, deadline)) {
    throw TimeoutError("could not send to " + describe() +
                       " in time: flow control (RTS/CTS, XON/XOFF) holding the line?");
  }
  if (result) throw disconnected(result.message());
}

bool SerialLink::finishOrCancel(const bool& done, Clock::time_point deadline) {
  if (runIoUntil(
          io_, [&] { return done; }, deadline))
    return true;
  // Cancel the operation and let its handler run, so nothing refers to the caller's locals.
  boost::system::error_code ignored;
  stream_.cancel(ignored);
  runIoUntil(
      io_, [&] { return done; }, Clock::now() + std::chrono::seconds(1));
  return false;
}

bool SerialLink::readSome(std::string& out, Clock::time_point deadline) {
  if (!isOpen()) throw DisconnectedError(describe() + " is not open");
  bool done = false;
  boost::system::error_code result;
  std::size_t got = 0;
  stream_.async_read_some(boost::asio::buffer(buffer_),
                          [&](const boost::system::error_code& ec, std::size_t n) {
                            result = ec;
                            got = n;
                            done = true;
                          });
  if (!finishOrCancel(done, deadline)) {
    if (!result || result == boost::asio::error::operation_aborted) {
      out.append(buffer_.data(), got);
      return got > 0;
    }
  }
  if (result == boost::asio::error::operation_aborted) return got > 0;
  if (result) throw disconnected(result.message());
  out.append(buffer_.data(), got);
  return got > 0;
}

void SerialLink::discardInput() {
  if (!isOpen()) return;
  ::tcflush(stream_.native_handle(), TCIFLUSH);
}

}  // namespace robocal::drivers
