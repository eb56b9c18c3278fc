#include "cellsim.hpp"
#include "val_texts.hpp"

#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/transport.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/path_motion.hpp>
#include <robocal/kinematics/sample.hpp>
#include <robocal/kinematics/units.hpp>
#include <robocal/sim/true_robot_json.hpp>

#include <boost/asio/io_context.hpp>
#include <boost/asio/local/stream_protocol.hpp>
#include <boost/asio/posix/stream_descriptor.hpp>
#include <boost/asio/read_until.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/streambuf.hpp>
#include <boost/asio/write.hpp>

#include <fcntl.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <deque>
#include <functional>
#include <istream>
#include <memory>
#include <random>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace robocal::cellsim {
namespace {

namespace asio = boost::asio;
using drivers::Clock;
using drivers::Joints6;

JointsDeg toJoints(const Joints6& a) {
  JointsDeg q;
  for (int i = 0; i < 6; ++i) q[i] = a[i];
  return q;
}

Joints6 toArray(const JointsDeg& q) {
  Joints6 a{};
  for (int i = 0; i < 6; ++i) a[i] = q[i];
  return a;
}

double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

speed_t speedFor(int baud) {
  const speed_t speed = drivers::termiosSpeed(baud);
  return speed ? speed : B9600;
}

// What a receiver at the wrong baud rate makes of text: bytes, but not text.
std::string garble(std::string_view bytes) {
  std::string out;
  for (char c : bytes)
    out.push_back(static_cast<char>(((static_cast<unsigned char>(c) * 7) ^ 0xA5) | 0x80));
  return out;
}

// One pty pair: the simulator holds the master (and a slave descriptor, so that the pty survives
// drivers opening and closing the slave); drivers open the slave by its path or the symlink.
class PtyPort {
 public:
  using BytesHandler = std::function<void(std::string_view)>;
  PtyPort(asio::io_context& io, std::string name, std::string link, int baud)
      : io_(io), name_(std::move(name)), link_(std::move(link)), baud_(baud), master_(io) {}
  ~PtyPort() { close(); }

  void setHandler(BytesHandler h) { handler_ = std::move(h); }
  bool isOpen() const { return master_.is_open(); }
  const std::string& slavePath() const { return slave_path_; }
  const std::string& name() const { return name_; }

  void open() {
    const int m = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (m < 0 || ::grantpt(m) != 0 || ::unlockpt(m) != 0)
      throw std::runtime_error(name_ + ": cannot create a pseudo-terminal");
    char path[256];
    if (::ptsname_r(m, path, sizeof path) != 0) throw std::runtime_error(name_ + ": no pty name");
    slave_path_ = path;
    slave_fd_ = ::open(path, O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (slave_fd_ < 0) throw std::runtime_error(name_ + ": cannot open " + slave_path_);
    termios t{};
    ::tcgetattr(slave_fd_, &t);
    ::cfmakeraw(&t);
    ::cfsetispeed(&t, speedFor(baud_));
    ::cfsetospeed(&t, speedFor(baud_));
    ::tcsetattr(slave_fd_, TCSANOW, &t);
    master_.assign(m);
    if (!link_.empty()) {
      const std::string tmp = link_ + ".new";
      ::unlink(tmp.c_str());
      if (::symlink(slave_path_.c_str(), tmp.c_str()) != 0 ||
          ::rename(tmp.c_str(), link_.c_str()) != 0)
        throw std::runtime_error(name_ + ": cannot create the link " + link_);
    }
    alive_ = std::make_shared<int>(0);
    read();
  }

  // An unplugged adapter: the pty goes away (drivers see a hang-up) and so does the link.
  void close() {
    alive_.reset();
    boost::system::error_code ec;
    if (master_.is_open()) master_.close(ec);
    if (slave_fd_ >= 0) ::close(slave_fd_);
    slave_fd_ = -1;
    if (!link_.empty()) ::unlink(link_.c_str());
    queue_.clear();
    writing_ = false;
  }

  // The slave is set to another baud rate than the device's.
  bool baudMismatch() const {
    if (slave_fd_ < 0) return false;
    termios t{};
    if (::tcgetattr(slave_fd_, &t) != 0) return false;
    return ::cfgetospeed(&t) != speedFor(baud_);
  }

  void write(std::string bytes) {
    if (!isOpen() || bytes.empty()) return;
    if (baudMismatch()) bytes = garble(bytes);
    if (queue_.size() > 256) return;  // nobody reads: the bytes go nowhere, as on a real line
    queue_.push_back(std::move(bytes));
    if (!writing_) writeNext();
  }

 private:
  void read() {
    std::weak_ptr<int> alive = alive_;
    master_.async_read_some(asio::buffer(buf_),
                            [this, alive](const boost::system::error_code& ec, std::size_t n) {
                              if (alive.expired()) return;
                              if (ec) {
                                if (ec != asio::error::operation_aborted)
                                  std::fprintf(stderr, "cellsim: %s: read error: %s\n",
                                               name_.c_str(), ec.message().c_str());
                                return;
                              }
                              if (handler_) handler_(std::string_view(buf_.data(), n));
                              if (!alive.expired() && isOpen()) read();
                            });
  }

  void writeNext() {
    if (queue_.empty()) {
      writing_ = false;
      return;
    }
    writing_ = true;
    std::weak_ptr<int> alive = alive_;
    asio::async_write(master_, asio::buffer(queue_.front()),
                      [this, alive](const boost::system::error_code& ec, std::size_t) {
                        if (alive.expired()) return;
                        queue_.pop_front();
                        if (ec) {
                          queue_.clear();
                          writing_ = false;
                          return;
                        }
                        writeNext();
                      });
  }

  asio::io_context& io_;
  std::string name_, link_;
  int baud_;
  asio::posix::stream_descriptor master_;
  int slave_fd_ = -1;
  std::string slave_path_;
  std::deque<std::string> queue_;
  bool writing_ = false;
  std::array<char, 1024> buf_{};
  BytesHandler handler_;
  std::shared_ptr<int> alive_;
};

struct BrokenEvent {
  double time_s;
  std::string connection;
  double deflection_mm;
};

class Cell {
 public:
  Cell(asio::io_context& io, const Options& o, const drivers::DriversConfig& config,
       const TrueRobot& truth)
      : io_(io),
        o_(o),
        val_dialect_(config.val),
        bar_config_(config.bar),
        truth_(truth.model),
        true_robot_(truth),
        ideal_(truth.realism.isIdeal()),
        kin_(truth.model),
        rng_(o.seed),
        val_(io, "val", o.val_link, o.val_baud),
        bar_(io, "bar", o.bar_link, o.bar_baud),
        tick_(io),
        stream_timer_(io),
        start_time_(Clock::now()) {
    if (!o.bar_mode.empty()) bar_config_.mode = o.bar_mode;
    where_layout_ = o.where_layout;
    where_layout_.joints_first = config.val.where_joints_first;
    completion_lines_ = o.val_completion_lines || isKawasaki(config.val.dialect);
    val_asking_ = o.val_boot_question;
    drivers::validate(bar_config_);
    joints_ = o.start_joints_deg;
    speed_ = o.speed_percent;
    move_re_ = drivers::templateRegex(config.val.move_joints_command, move_fields_);
    std::vector<std::string> unused;
    where_re_ = drivers::templateRegex(config.val.where_command, unused);
    abort_re_ = drivers::templateRegex(config.val.abort_command, unused);
    speed_re_ = drivers::templateRegex(config.val.speed_command, unused);
    if (!config.val.path_execute_command.empty()) {  // never matched otherwise
      path_edit_re_ = drivers::templateRegex(config.val.path_edit_command, unused);
      path_line_re_ = drivers::templateRegex(config.val.path_move_line, path_line_fields_);
      path_end_re_ = drivers::templateRegex(config.val.path_end_edit, unused);
      path_execute_re_ = drivers::templateRegex(config.val.path_execute_command, unused);
    }
    connectBar(o.connection, o.extension_mm, o.bar_here ? -1 : o.bar_mm);
    val_.setHandler([this](std::string_view b) { valBytes(b); });
    bar_.setHandler([this](std::string_view b) { barBytes(b); });
  }

  void start() {
    val_.open();
    bar_.open();
    std::printf("val %s%s\nbar %s%s\n", val_.slavePath().c_str(),
                o_.val_link.empty() ? "" : (" -> " + o_.val_link).c_str(), bar_.slavePath().c_str(),
                o_.bar_link.empty() ? "" : (" -> " + o_.bar_link).c_str());
    std::fflush(stdout);
    tick();
    if (bar_config_.mode == "streamed") stream();
  }

  void shutdown() {
    val_.close();
    bar_.close();
    tick_.cancel();
    stream_timer_.cancel();
  }

  // ------------------------------------------------------------------------------ control
  std::string control(const std::string& text) {
    std::istringstream in(text);
    std::vector<std::string> w;
    for (std::string s; in >> s;) w.push_back(s);
    if (w.empty()) return "error: empty command";
    const auto port = [&](const std::string& name) -> PtyPort& {
      if (name == "val") return val_;
      if (name == "bar") return bar_;
      throw std::invalid_argument("no device '" + name + "' (val or bar)");
    };
    const auto seconds = [&](std::size_t i, double fallback) {
      return w.size() > i ? std::stod(w[i]) : fallback;
    };
    try {
      if (w[0] == "status") return "ok " + status();
      if (w[0] == "events") {
        std::string out = "ok " + std::to_string(events_.size());
        char buf[160];
        for (const auto& e : events_) {
          std::snprintf(buf, sizeof buf, " time_s=%.3f,connection=%s,deflection_mm=%+.3f", e.time_s,
                        e.connection.c_str(), e.deflection_mm);
          out += buf;
        }
        return out;
      }
      if (w[0] == "quit") {
        io_.stop();
        return "ok bye";
      }
      if (w[0] == "estop") {
        estop();
        return "ok estop";
      }
      if (w[0] == "reset") {
        estop_ = false;
        return "ok reset";
      }
      if (w[0] == "connect" && w.size() >= 2) {
        double ext = 0, bar = o_.bar_mm;
        for (std::size_t i = 2; i < w.size(); ++i) {
          const auto eq = w[i].find('=');
          const std::string key = w[i].substr(0, eq),
                            value = eq == std::string::npos ? "" : w[i].substr(eq + 1);
          if (key == "extension_mm")
            ext = std::stod(value);
          else if (key == "bar_mm")
            bar = value == "here" ? -1 : std::stod(value);
          else
            throw std::invalid_argument("unknown connect option '" + key + "'");
        }
        connectBar(w[1], ext, bar);
        return "ok " + status();
      }
      if (w[0] == "fault" && w.size() >= 2) {
        const std::string& f = w[1];
        const bool val = w.size() > 2 && w[2] == "val";
        if (f == "completion")  // a completion line inside the next WHERE reply
          completion_next_ = true;
        else if (f == "garbage" && val)
          val_garbage_next_ = true;
        else if (f == "drop" && val)
          val_drop_next_ = true;
        else if (f == "garbage")
          garbage_next_ = true;
        else if (f == "drop")
          drop_next_ = true;
        else if (f == "noprobe")
          no_probe_ = !(w.size() > 2 && w[2] == "off");
        else if (f == "loose")  // a ball loose in its socket: the attached bar reads unsteadily
          loose_ = !(w.size() > 2 && w[2] == "off");
        else if (f == "error") {
          std::string msg;
          for (std::size_t i = 2; i < w.size(); ++i) msg += (msg.empty() ? "" : " ") + w[i];
          error_next_ = msg.empty() ? o_.val_error_text : msg;
        } else if (f == "stall" && w.size() >= 3) {
          stallUntil(w[2]) = Clock::now() + toDuration(seconds(3, o_.stall_s));
        } else if (f == "disconnect" && w.size() >= 3) {
          disconnect(port(w[2]), seconds(3, o_.reconnect_after_s));
        } else {
          return "error: unknown fault (garbage, drop, completion, noprobe [off], loose [off], "
                 "error [TEXT], "
                 "stall val|bar "
                 "S, "
                 "disconnect val|bar S)";
        }
        return "ok fault " + f;
      }
    } catch (const std::exception& e) {
      return std::string("error: ") + e.what();
    }
    return "error: unknown command (status, events, connect B1C1 [extension_mm=E] [bar_mm=L|here], "
           "estop, "
           "reset, fault ..., quit)";
  }

  const std::vector<BrokenEvent>& events() const { return events_; }

 private:
  static Clock::duration toDuration(double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  }
  Clock::time_point& stallUntil(const std::string& device) {
    if (device == "val") return val_stall_until_;
    if (device == "bar") return bar_stall_until_;
    throw std::invalid_argument("no device '" + device + "' (val or bar)");
  }

  std::string status() const {
    char buf[512];
    bool connected = false;
    const double d = deflection(connected);
    std::snprintf(buf, sizeof buf,
                  "joints_deg=%.3f,%.3f,%.3f,%.3f,%.3f,%.3f moving=%d estop=%d speed=%.0f "
                  "connection=%s bar_mm=%.3f extension_mm=%.3f deflection_mm=%.4f "
                  "ring_mm=%.4f broken_events=%zu val=%s bar=%s moves=%ld paths=%ld "
                  "moving_peak_mm=%.4f",
                  joints_[0], joints_[1], joints_[2], joints_[3], joints_[4], joints_[5],
                  moving_ ? 1 : 0, estop_ ? 1 : 0, speed_, connection_name_.c_str(), bar_mm_,
                  extension_mm_, connected ? d : 0.0, ring(), events_.size(),
                  val_.isOpen() ? val_.slavePath().c_str() : "-",
                  bar_.isOpen() ? bar_.slavePath().c_str() : "-", moves_, paths_, moving_peak_mm_);
    return buf;
  }

  void connectBar(const std::string& name, double extension_mm, double bar_mm) {
    if (name == "none") {
      connected_ = false;
      connection_name_ = "none";
      over_ = false;
      return;
    }
    const auto list = parseConnections(name);
    if (list.size() != 1) throw std::invalid_argument("connect one ball to one chuck, e.g. B1C2");
    const Connection previous = connection_;
    connection_ = list[0];
    // A bar whose ends are further apart (or closer) than its travel cannot be seated: the
    // operator cannot attach it, and the robot has to move first.
    const double length = bar_mm >= 0 ? bar_mm : trueLength() - extension_mm;
    const double misfit =
        trueLength() - (length + extension_mm) * (1 + true_robot_.realism.bar_length_error);
    if (std::abs(misfit) > o_.range_mm) {
      connection_ = previous;
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "does not fit: the bar would be %s by %.3f mm (range +/-%.3f mm); move the "
                    "ball by %+.3f mm along the bar and connect again",
                    misfit > 0 ? "stretched" : "compressed", std::abs(misfit), o_.range_mm,
                    -misfit);
      throw std::invalid_argument(buf);
    }
    connected_ = true;
    connection_name_ = connectionName(connection_);
    extension_mm_ = extension_mm;
    // bar_mm < 0: a bar of exactly the current length (handy for tests and demos).
    bar_mm_ = length;
    over_ = false;
    checkBar();
  }

  // The distance between the connected ball's and chuck's centres (mm): the true robot's, with
  // its realism (backlash by each joint's last direction, gravity compliance, the warm-up at this
  // cell time).
  double trueLength() const {
    const JointsDeg j = toJoints(joints_);
    const Eigen::Vector3d& ball = truth_.balls_mm[connection_.ball_index];
    const Eigen::Vector3d& chuck = truth_.chucks_mm[connection_.chuck_index];
    if (ideal_) return kin_.barLength(j, ball, chuck);
    return warmKinematics().barLength(true_robot_.effectiveReadings(j, approach_), ball, chuck);
  }

  // The true robot's geometry at this cell time, rebuilt every few cell seconds of the warm-up.
  const Kinematics& warmKinematics() const {
    const double minutes = secondsSince(start_time_) * o_.time_scale / 60.0;
    if (true_robot_.realism.warmup_k == 0) return kin_;
    if (!warm_kin_ || std::abs(minutes - warm_minutes_) > 0.05) {
      warm_minutes_ = minutes;
      warm_kin_.emplace(true_robot_.modelAt(minutes));
    }
    return *warm_kin_;
  }

  // The bar's physical deflection (mm): the travel of its LVDT from the bar's true length (its
  // stated length with the bar-length standard's error). What breaks the bar.
  double deflection(bool& connected) const {
    connected = connected_;
    if (!connected_) return 0.0;
    const double stated_mm = bar_mm_ + extension_mm_;
    return trueLength() - stated_mm * (1 + true_robot_.realism.bar_length_error);
  }

  // What the LVDT reads for that deflection: its gain error and nonlinearity (TrueRobot).
  double lvdtReading(double deflection_mm) const {
    const double stated_mm = bar_mm_ + extension_mm_;
    const double true_mm = deflection_mm + stated_mm * (1 + true_robot_.realism.bar_length_error);
    return true_robot_.measuredLength(true_mm, stated_mm) - stated_mm;
  }

  void checkBar() {
    bool connected = false;
    const double d = deflection(connected);
    if (!connected) return;
    if (moving_) moving_peak_mm_ = std::max(moving_peak_mm_, std::abs(d));
    if (std::abs(d) > o_.range_mm) {
      if (!over_) {
        events_.push_back({secondsSince(start_time_), connection_name_, d});
        std::fprintf(stderr,
                     "cellsim: THE BAR WOULD HAVE BROKEN: %s %s by %.3f mm (range +/-%.3f mm) at "
                     "joints %.3f %.3f %.3f %.3f %.3f %.3f\n",
                     connection_name_.c_str(), d > 0 ? "stretched" : "compressed", std::abs(d),
                     o_.range_mm, joints_[0], joints_[1], joints_[2], joints_[3], joints_[4],
                     joints_[5]);
      }
      over_ = true;
    } else {
      over_ = false;
    }
  }

  // ------------------------------------------------------------------------------ robot
  void tick() {
    if (moving_) {
      const double t = secondsSince(move_t0_);
      joints_ = toArray(motion_->at(t));
      if (t >= motion_->durationS()) {
        moving_ = false;
        motionEnded();
        // The ring starts when the motion ended, not at this tick.
        ring_t0_ = move_t0_ + toDuration(motion_->durationS());
        ring_mm_ = o_.settling.amplitudeFor(move_travel_mm_);
      }
      if (estop_at_ && t >= *estop_at_) {
        estop_at_.reset();
        estop();
      }
    }
    checkBar();
    tick_.expires_after(std::chrono::milliseconds(5));
    tick_.async_wait([this](const boost::system::error_code& ec) {
      if (!ec) tick();
    });
  }

  void estop() {
    moving_ = false;
    estop_ = true;
    estop_at_.reset();
    std::fprintf(stderr, "cellsim: E-STOP\n");
    if (Clock::now() >= val_stall_until_)
      val_.write(o_.val_eol + valErrorLine(dialect(), ValFault::kPowerOff) + o_.val_eol +
                 val_dialect_.idlePrompt());
    val_busy_ = false;
    typedAhead();
  }

  const std::string& dialect() const { return val_dialect_.config().dialect; }
  const std::string& prompt() const {
    return moving_ ? val_dialect_.busyPrompt() : val_dialect_.idlePrompt();
  }

  // A move ended: the completion line (AS), and a synchronous move's prompt at last, then the
  // lines typed while it ran.
  void motionEnded() {
    if (completion_lines_) val_.write(o_.val_eol + kCompletionLine + o_.val_eol);
    if (!val_busy_) return;
    val_busy_ = false;
    val_.write(o_.val_eol + val_dialect_.idlePrompt());
    typedAhead();
  }

  void typedAhead() {
    while (!val_busy_ && !val_typeahead_.empty() && val_.isOpen()) {
      std::string line = std::move(val_typeahead_.front());
      val_typeahead_.pop_front();
      if (o_.val_echo) val_.write(line);
      valLine(line);
    }
  }

  Joints6 quantised() const {
    Joints6 q = joints_;
    if (o_.quantum_deg > 0)
      for (double& v : q) v = std::round(v / o_.quantum_deg) * o_.quantum_deg;
    return q;
  }

  Eigen::Vector3d toolPosition(const Joints6& joints_deg) const {
    return kin_.toolPose(toJoints(joints_deg)).translation();
  }

  // The tool's ringing along the bar now (settling.hpp), in cell time (time_scale).
  double ring() const {
    if (moving_) return 0;  // the model starts at the end of a move
    return o_.settling.ring(ring_mm_, secondsSince(ring_t0_) * o_.time_scale);
  }

  drivers::Location6 location() const {
    const JointsDeg j = toJoints(joints_);
    const Eigen::Isometry3d pose = kin_.toolPose(j);
    const Eigen::Vector3d oat = pose.linear().eulerAngles(2, 1, 2) * kDegPerRad;
    const Eigen::Vector3d p = pose.translation();
    return {p.x(), p.y(), p.z(), oat[0], oat[1], oat[2]};
  }

  // ------------------------------------------------------------------------------ VAL II
  void valBytes(std::string_view bytes) {
    if (val_.baudMismatch()) {
      val_.write(std::string(bytes));  // the echo, garbled on the way back
      return;
    }
    if (Clock::now() < val_stall_until_) return;  // a hung controller loses its input
    std::string echo;
    for (char c : bytes) {
      if (c == '\r' || c == '\n') {
        const bool second_half = c == '\n' && val_after_cr_;
        val_after_cr_ = c == '\r';
        if (second_half) continue;
        std::string line = std::move(val_line_);
        val_line_.clear();
        if (val_busy_) {  // a synchronous move runs: the monitor reads the line when it ends
          val_typeahead_.push_back(std::move(line));
          echo.clear();
          continue;
        }
        if (o_.val_echo) val_.write(std::move(echo));
        echo.clear();
        valLine(line);
        if (!val_.isOpen()) return;
      } else {
        val_after_cr_ = false;
        val_line_.push_back(c);
        echo.push_back(c);
      }
    }
    if (o_.val_echo && !val_busy_) val_.write(std::move(echo));
  }

  void valLine(const std::string& raw) {
    const std::string line = drivers::trim(raw);
    const std::string& eol = o_.val_eol;
    if (val_asking_) {  // just booted: nothing but the answer is read
      const std::string answer = drivers::toUpper(line);
      if (answer == "Y" || answer == "N") {
        val_asking_ = false;
        val_.write(eol + val_dialect_.idlePrompt());
      } else {
        val_.write(eol + kBootQuestion);
      }
      return;
    }
    if (line.empty()) {
      val_.write(eol + prompt());
      return;
    }
    ++val_commands_;
    if (o_.verbose) std::fprintf(stderr, "cellsim: val < %s\n", line.c_str());
    if (o_.val_disconnect_after > 0 && val_commands_ == o_.val_disconnect_after + 1) {
      disconnect(val_, o_.reconnect_after_s);
      return;
    }
    if (o_.val_stall_after > 0 && val_commands_ == o_.val_stall_after + 1) {
      val_stall_until_ = Clock::now() + toDuration(o_.stall_s);
      std::fprintf(stderr, "cellsim: val stalls for %.1f s\n", o_.stall_s);
      return;
    }
    std::vector<std::string> lines;
    if (o_.val_error_on_command > 0 && val_commands_ == o_.val_error_on_command)
      error_next_ = o_.val_error_text;
    if (!error_next_.empty()) {
      lines.push_back(valErrorLine(dialect(), error_next_));
      error_next_.clear();
    } else {
      lines = valCommand(line);
    }
    // A reply line lost or garbled on the wire (the last one: WHERE's joint values).
    if (!lines.empty()) {
      ++val_replies_;
      const auto every = [&](long n) { return n > 0 && val_replies_ % n == 0; };
      if (val_drop_next_ || every(o_.val_drop_every)) {
        val_drop_next_ = false;
        lines.pop_back();
      } else if (val_garbage_next_ || every(o_.val_garbage_every)) {
        val_garbage_next_ = false;
        lines.back().insert(lines.back().size() / 2, std::string("\x93\xF1\xFE", 3));
      }
    }
    std::string out = eol;
    for (const auto& l : lines) out += l + eol;
    val_.write(val_busy_ ? out : out + prompt());  // a synchronous move: no prompt yet
  }

  std::vector<std::string> valCommand(const std::string& line) {
    std::smatch m;
    // An editor reads every line as a program line: WHERE or ABORT typed into it do nothing.
    if (editing_) return programLine(line);
    if (std::regex_match(line, m, where_re_)) {
      auto lines =
          drivers::formatWhere(val_dialect_.config(), where_layout_, location(), quantised());
      if (completion_next_) {  // printed by the controller while it wrote the reply
        completion_next_ = false;
        lines.insert(lines.begin() + 1, kCompletionLine);
      }
      return lines;
    }
    if (std::regex_match(line, m, abort_re_)) {
      moving_ = false;
      estop_at_.reset();
      return {};
    }
    if (std::regex_match(line, m, speed_re_)) {
      const double s = std::stod(m[1].str());
      if (!(s > 0 && s <= 100)) return {valErrorLine(dialect(), ValFault::kInvalidSpeed)};
      speed_ = s;
      return {};
    }
    if (std::regex_match(line, m, path_edit_re_)) {
      editing_ = true;  // a fresh program: what was there before is replaced
      program_.clear();
      return {};
    }
    if (std::regex_match(line, m, path_execute_re_)) {
      if (program_.empty()) return {valErrorLine(dialect(), ValFault::kUnknownCommand)};
      ++paths_;
      return startMotion(program_, o_.blend_deg);
    }
    if (std::regex_match(line, m, move_re_)) return startMotion({jointsOf(m, move_fields_)}, 0);
    return {valErrorLine(dialect(), ValFault::kUnknownCommand)};
  }

  Joints6 jointsOf(const std::smatch& m, const std::vector<std::string>& fields) const {
    Joints6 j{};
    for (std::size_t i = 0; i < fields.size(); ++i)
      j[std::stoi(fields[i].substr(1)) - 1] = std::stod(m[i + 1].str());
    return j;
  }

  // A line typed while a path program is edited: a step, or the end of the editing.
  std::vector<std::string> programLine(const std::string& line) {
    std::smatch m;
    if (std::regex_match(line, m, path_end_re_)) {
      editing_ = false;
      return {};
    }
    if (!std::regex_match(line, m, path_line_re_))
      return {valErrorLine(dialect(), ValFault::kUnknownCommand)};
    program_.push_back(jointsOf(m, path_line_fields_));
    return {};
  }

  // A DO MOVE (one waypoint, no blend) or a path program's run (blended,
  // robocal/kinematics/path_motion.hpp).
  std::vector<std::string> startMotion(const std::vector<Joints6>& targets, double blend_deg) {
    if (estop_) return {valErrorLine(dialect(), ValFault::kPowerOff)};
    std::vector<JointsDeg> waypoints;
    for (const Joints6& target : targets) {
      for (int k = 0; k < 6; ++k)
        if (target[k] < truth_.joints[k].min_deg || target[k] > truth_.joints[k].max_deg)
          return {valErrorLine(dialect(), ValFault::kOutOfRange)};
      waypoints.push_back(toJoints(target));
    }
    ++moves_;
    motion_.emplace(toJoints(joints_), waypoints,
                    o_.joint_speed_deg_s * speed_ / 100.0 * o_.time_scale, blend_deg);
    // Each joint's backlash takes the side of its last motion along the path.
    JointsDeg from = toJoints(joints_);
    for (const JointsDeg& to : waypoints) {
      approach_ = approachOf(from, to, approach_);
      from = to;
    }
    move_travel_mm_ =
        (toolPosition(toArray(motion_->target())) - toolPosition(toArray(motion_->lastFrom())))
            .norm();
    move_t0_ = Clock::now();
    moving_ = true;
    const double duration_s = motion_->durationS();
    if (o_.estop_on_move > 0 && moves_ == o_.estop_on_move) estop_at_ = duration_s / 2;
    val_busy_ = o_.val_sync_moves && duration_s > 0;
    return {};
  }

  // ------------------------------------------------------------------------------ ball-bar
  void barBytes(std::string_view bytes) {
    if (bar_.baudMismatch()) return;  // garbled commands are not understood
    if (Clock::now() < bar_stall_until_) return;
    std::vector<std::string> lines;
    bar_splitter_.feed(bytes, lines);
    if (bar_config_.mode != "polled") return;
    for (const auto& l : lines)
      if (drivers::toUpper(drivers::trim(l)) == drivers::toUpper(bar_config_.poll_command))
        barLine();
  }

  void stream() {
    barLine();
    stream_timer_.expires_after(toDuration(1.0 / o_.stream_hz));
    stream_timer_.async_wait([this](const boost::system::error_code& ec) {
      if (!ec) stream();
    });
  }

  void barLine() {
    if (!bar_.isOpen() || Clock::now() < bar_stall_until_) return;
    ++bar_lines_;
    if (o_.bar_disconnect_after > 0 && bar_lines_ == o_.bar_disconnect_after + 1) {
      disconnect(bar_, o_.reconnect_after_s);
      return;
    }
    if (o_.bar_stall_after > 0 && bar_lines_ == o_.bar_stall_after + 1) {
      bar_stall_until_ = Clock::now() + toDuration(o_.stall_s);
      return;
    }
    if (drop_next_ || (o_.bar_drop_every > 0 && bar_lines_ % o_.bar_drop_every == 0)) {
      drop_next_ = false;
      return;
    }
    std::string line = barText();
    const std::string eol = "\r\n";
    if (garbage_next_ || (o_.bar_garbage_every > 0 && bar_lines_ % o_.bar_garbage_every == 0)) {
      garbage_next_ = false;
      ++garbage_count_;
      std::uniform_int_distribution<int> pos(0, static_cast<int>(line.size()));
      if (garbage_count_ % 2 == 1) {
        // Noise on the line: bytes that are not text inside the reading.
        line.insert(static_cast<std::size_t>(pos(rng_)), std::string("\x93\xF1\x02\xFE", 4));
      } else {
        // A line cut short: the rest of it is lost, the next one runs into it.
        bar_.write(line.substr(0, static_cast<std::size_t>(pos(rng_))) + "\xC3");
        line = barText();
      }
    }
    bar_.write(line + eol);
  }

  std::string barText() {
    using drivers::BarLineKind;
    if (no_probe_ || o_.bar_no_probe) return drivers::formatBarStatus(BarLineKind::kNoProbe);
    bool connected = false;
    const double d = deflection(connected);
    if (connected && std::abs(d) > o_.range_mm)
      return drivers::formatBarStatus(BarLineKind::kOverRange, d < 0);
    std::normal_distribution<double> noise(0.0, o_.noise_mm), play(0.0, kLoosePlayMm);
    const double value_mm = (connected ? lvdtReading(d) + ring() : 0.0) +
                            (o_.noise_mm > 0 ? noise(rng_) : 0.0) +
                            (loose_ && connected ? play(rng_) : 0.0);
    return drivers::formatBarReading(bar_config_.format, value_mm / bar_config_.unit_scale_mm);
  }

  void disconnect(PtyPort& port, double reconnect_after_s) {
    std::fprintf(stderr, "cellsim: %s disconnected for %.2f s\n", port.name().c_str(),
                 reconnect_after_s);
    port.close();
    if (&port == &val_) {
      val_line_.clear();
      val_typeahead_.clear();
    }
    auto timer = std::make_shared<asio::steady_timer>(io_, toDuration(reconnect_after_s));
    timer->async_wait([this, &port, timer](const boost::system::error_code& ec) {
      if (ec) return;
      port.open();
      std::printf("%s %s\n", port.name().c_str(), port.slavePath().c_str());
      std::fflush(stdout);
    });
  }

  asio::io_context& io_;
  const Options& o_;
  drivers::ValDialect val_dialect_;
  drivers::BarConfig bar_config_;
  Model truth_;
  TrueRobot true_robot_;
  bool ideal_;      // the truth is exactly its model: the cold geometry alone
  Kinematics kin_;  // the true geometry, cold
  Approach approach_ = kPositiveApproach;
  mutable std::optional<Kinematics> warm_kin_;
  mutable double warm_minutes_ = 0;
  std::mt19937_64 rng_;
  PtyPort val_, bar_;
  asio::steady_timer tick_, stream_timer_;
  Clock::time_point start_time_;

  // robot
  Joints6 joints_{};
  std::optional<PathMotion> motion_;  // the current (or last) motion
  bool moving_ = false, estop_ = false;
  Clock::time_point move_t0_{};
  double speed_ = 50;
  double move_travel_mm_ = 0;       // tool travel of the current move
  Clock::time_point ring_t0_{};     // the end of the last move
  double ring_mm_ = 0;              // its ringing's starting amplitude
  std::optional<double> estop_at_;  // seconds into the current move
  long moves_ = 0, paths_ = 0;      // motions started; of which path programs
  double moving_peak_mm_ = 0;       // the largest |deflection| while moving, since the start
  // VAL II
  std::regex move_re_, where_re_, abort_re_, speed_re_;
  std::vector<std::string> move_fields_;
  std::regex path_edit_re_, path_line_re_, path_end_re_, path_execute_re_;
  std::vector<std::string> path_line_fields_;
  bool editing_ = false;          // a path program is being written (EDIT ... E)
  std::vector<Joints6> program_;  // its steps
  std::string val_line_;
  bool val_after_cr_ = false;
  drivers::WhereLayout where_layout_;
  bool completion_lines_ = false, completion_next_ = false;
  bool val_busy_ = false;                  // a synchronous move runs
  bool val_asking_ = false;                // the boot question is unanswered
  std::deque<std::string> val_typeahead_;  // lines received while val_busy_
  long val_commands_ = 0;
  Clock::time_point val_stall_until_{}, bar_stall_until_{};
  std::string error_next_;
  // bar
  Connection connection_;
  bool connected_ = false, over_ = false, no_probe_ = false, loose_ = false;
  static constexpr double kLoosePlayMm = 0.25;  // 1 sigma of a loose ball's play
  std::string connection_name_ = "none";
  double bar_mm_ = 100, extension_mm_ = 0;
  std::vector<BrokenEvent> events_;
  drivers::LineSplitter bar_splitter_;
  long bar_lines_ = 0, garbage_count_ = 0;
  bool garbage_next_ = false, drop_next_ = false, val_garbage_next_ = false, val_drop_next_ = false;
  long val_replies_ = 0;
};

// Line commands from a stream (a unix-socket client or stdin), one reply line each.
template <typename Stream>
class ControlSession : public std::enable_shared_from_this<ControlSession<Stream>> {
 public:
  ControlSession(Stream stream, Cell& cell) : stream_(std::move(stream)), cell_(cell) {}
  void start() { read(); }

 private:
  void read() {
    auto self = this->shared_from_this();
    asio::async_read_until(
        stream_, buffer_, '\n', [self](const boost::system::error_code& ec, std::size_t) {
          if (ec) return;
          std::istream in(&self->buffer_);
          std::string line;
          std::getline(in, line);
          self->reply_ = self->cell_.control(line) + "\n";
          asio::async_write(self->stream_, asio::buffer(self->reply_),
                            [self](const boost::system::error_code& e, std::size_t) {
                              if (!e) self->read();
                            });
        });
  }
  Stream stream_;
  Cell& cell_;
  asio::streambuf buffer_;
  std::string reply_;
};

void accept(asio::local::stream_protocol::acceptor& acceptor, Cell& cell) {
  acceptor.async_accept([&acceptor, &cell](const boost::system::error_code& ec,
                                           asio::local::stream_protocol::socket socket) {
    if (ec) return;
    std::make_shared<ControlSession<asio::local::stream_protocol::socket>>(std::move(socket), cell)
        ->start();
    accept(acceptor, cell);
  });
}

}  // namespace

int run(const Options& o) {
  TrueRobot truth = loadTruthFile(o.model_path);
  if (!o.realism.empty()) truth.realism = realismNamed(o.realism, truth.realism.compliance.load);
  const drivers::DriversConfig config =
      o.config_path.empty() ? drivers::DriversConfig{} : drivers::loadDriversConfig(o.config_path);
  asio::io_context io;
  Cell cell(io, o, config, truth);
  cell.start();

  std::unique_ptr<asio::local::stream_protocol::acceptor> acceptor;
  if (!o.control_path.empty()) {
    ::unlink(o.control_path.c_str());
    acceptor = std::make_unique<asio::local::stream_protocol::acceptor>(
        io, asio::local::stream_protocol::endpoint(o.control_path));
    accept(*acceptor, cell);
    std::printf("control %s\n", o.control_path.c_str());
  }
  // Control lines on stdin, replies on stdout. The stream, its buffer and the read loop live
  // for the whole run.
  asio::posix::stream_descriptor stdin_stream(io);
  asio::streambuf stdin_buffer;
  std::function<void()> read_stdin = [&]() {
    asio::async_read_until(stdin_stream, stdin_buffer, '\n',
                           [&](const boost::system::error_code& ec, std::size_t) {
                             if (ec) return;  // end of input: the socket may still be used
                             std::istream is(&stdin_buffer);
                             std::string line;
                             std::getline(is, line);
                             std::printf("%s\n", cell.control(line).c_str());
                             std::fflush(stdout);
                             read_stdin();
                           });
  };
  if (o.stdin_control) {
    stdin_stream.assign(::dup(STDIN_FILENO));
    read_stdin();
  }
  std::printf("ready\n");
  std::fflush(stdout);

  asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code&, int) { io.stop(); });
  io.run();
  cell.shutdown();
  if (!o.control_path.empty()) ::unlink(o.control_path.c_str());
  std::fprintf(stderr, "cellsim: stopped; %zu bar-would-have-broken event(s)\n",
               cell.events().size());
  return 0;
}

}  // namespace robocal::cellsim
