// robocal-bench-stream: streaming latency and fan-out of robocald (issue 7, item 1; the figures
// are in docs/reliability.md, section 1).
//
// For each configuration it starts robocal-cellsim (the ball-bar streaming at --stream-hz) and a
// fresh robocald, connects N watchers, one status client (polls `status` once a second, does not
// watch) and, unless told not to, one stuck client (sends `watch`, then never reads). After a
// warm-up it measures for --duration-s: every BAR line carries t_us, the daemon's steady clock
// when the reader's line ended in the driver; a watcher on this machine takes its own steady
// clock when recv() returns and, before parsing, latency = receive time - t_us. Per
// configuration: latency p50/p99/max over all readings x watchers, readings dropped per watcher
// (gaps in seq), daemon CPU (utime+stime from /proc/PID/stat over the window), RSS at the start,
// middle and end of the window and its peak (VmHWM), and when the daemon closed the stuck client
// (its log line "client N (127.0.0.1:PORT) closed: ...").
//
// The watchers are read by one epoll thread with non-blocking sockets; lines are cut and the two
// numbers found with string searches, no JSON parser. The bench's own CPU is reported too, so
// that one can see it is not the bottleneck.
//
// usage: robocal-bench-stream [options]
//   --watchers 1,16,64     watcher counts, each run with the stuck client           [1,16,64]
//   --no-compare           leave out the run at the largest count without the stuck client
//   --stuck-rcvbuf-bytes N one more run at the largest count, the stuck client's SO_RCVBUF
//                          set to N: its kernel stops taking data early, so the daemon's own
//                          bound (unsent bytes, queue, client_stall_s) shows; 0: no such run
//                          [65536]
//   --duration-s S         measurement window per configuration                     [30]
//   --warmup-s S           after connecting, before the window                      [2]
//   --stream-hz F          bar readings per second (cellsim --stream-hz)            [200]
//   --stuck-wait-s S       after the window, wait this long more for the daemon to
//                          close the stuck client (the watchers keep reading)        [0]
//   --client-stall-s S     robocald's client_stall_s          [not set: the daemon's default]
//   --client-queue-max N   robocald's client_queue_max        [not set: the daemon's default]
//   --daemon-nice N        run robocald at nice N (e.g. -10, as root: how much of the tail is
//                          the machine's other load)                    [0: not changed]
//   --bench-slice-us U     ask for this EEVDF time slice for the measuring thread (Linux 6.12+)
//                          so that it wakes sooner on a loaded machine           [0: default]
//   --cellsim PATH, --robocald PATH   [next to this binary in the build tree]
//   --model FILE, --cell FILE         [config/puma560.json, config/cell.json of the sources]
//   --work-dir DIR         logs and configs kept there        [a fresh folder in /tmp, removed]
//   --browsers N           also N WebSocket watchers on robocald's web port (the console's
//                          browsers, bench/browser_load.hpp)                         [0]
//   --json                 one JSON object on stdout instead of the table
#include "browser_load.hpp"

#include <nlohmann/json.hpp>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sched.h>
#include <signal.h>
#include <sys/epoll.h>
#include <sys/ioctl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/types.h>
#include <sys/uio.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <tuple>
#include <vector>

#ifndef ROBOCAL_SOURCE_DIR
#define ROBOCAL_SOURCE_DIR "."
#endif

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;  // CLOCK_MONOTONIC, as the daemon's t_us

std::int64_t nowUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(Clock::now().time_since_epoch())
      .count();
}

double sinceS(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

struct Options {
  std::string cellsim, robocald, model, cell, work_dir;
  std::vector<int> watchers = {1, 16, 64};
  bool compare_without_stuck = true;
  double duration_s = 30, warmup_s = 2, stream_hz = 200, stuck_wait_s = 0;
  double client_stall_s = -1;
  long client_queue_max = -1;
  int stuck_rcvbuf_bytes = 65536;
  int daemon_nice = 0;  // 0: as this process
  int bench_slice_us = 0;
  bool json_output = false;
  int browsers = 0;  // WebSocket watchers on the web port besides the TCP ones
};

// Asks for a short EEVDF time slice for this thread (Linux 6.12+; ignored before): an early
// deadline at each wake-up, so it runs without waiting for a CPU-bound neighbour's slice to end.
// 0: the kernel's default slice.
bool setSliceUs(int slice_us) {
  struct {
    std::uint32_t size;
    std::uint32_t sched_policy;
    std::uint64_t sched_flags;
    std::int32_t sched_nice;
    std::uint32_t sched_priority;
    std::uint64_t sched_runtime, sched_deadline, sched_period;
  } attr{};
  attr.size = sizeof attr;
  attr.sched_policy = SCHED_OTHER;
  attr.sched_nice = ::getpriority(PRIO_PROCESS, 0);
  attr.sched_runtime = static_cast<std::uint64_t>(slice_us) * 1000;
  return ::syscall(SYS_sched_setattr, 0, &attr, 0) == 0;
}

// ------------------------------------------------------------------------------ child processes
class Child {
 public:
  Child(const std::vector<std::string>& argv, const std::string& out_path,
        const std::string& err_path, int nice = 0)
      : out_path_(out_path), err_path_(err_path) {
    // A previous run's output in the same folder must not be taken for this one's.
    ::unlink(out_path.c_str());
    ::unlink(err_path.c_str());
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      const int out = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int err = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int in = ::open("/dev/null", O_RDONLY);
      if (out < 0 || err < 0 || in < 0) ::_exit(126);
      if (nice != 0 && ::setpriority(PRIO_PROCESS, 0, nice) != 0) ::_exit(125);
      setSliceUs(0);  // not this process's slice: the kernel's default, as when run alone
      ::dup2(in, 0);
      ::dup2(out, 1);
      ::dup2(err, 2);
      ::execv(args[0], args.data());
      std::fprintf(stderr, "exec %s: %s\n", args[0], std::strerror(errno));
      ::_exit(127);
    }
  }
  ~Child() { stop(); }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  pid_t pid() const { return pid_; }
  bool running() {
    if (pid_ <= 0) return false;
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      return false;
    }
    return true;
  }
  // SIGTERM, then SIGKILL after timeout_s.
  void stop(double timeout_s = 5.0) {
    if (!running()) return;
    ::kill(pid_, SIGTERM);
    const auto t0 = Clock::now();
    int status = 0;
    while (sinceS(t0) < timeout_s) {
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
  }
  // The first line of stdout containing `needle`; throws after timeout_s.
  std::string waitForLine(const std::string& needle, double timeout_s) {
    const auto t0 = Clock::now();
    while (sinceS(t0) < timeout_s) {
      std::ifstream in(out_path_);
      for (std::string line; std::getline(in, line);)
        if (line.find(needle) != std::string::npos) return line;
      if (!running())
        throw std::runtime_error("child exited before printing '" + needle + "'; see " + err_path_);
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    throw std::runtime_error("no '" + needle + "' from the child within " +
                             std::to_string(timeout_s) + " s; see " + err_path_);
  }

 private:
  pid_t pid_ = -1;
  std::string out_path_, err_path_;
};

// ------------------------------------------------------------------------------ /proc
double procCpuS(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto close = text.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream fields(text.substr(close + 2));
  std::vector<std::string> f;
  for (std::string s; fields >> s;) f.push_back(s);
  // f[0] is field 3 (state): utime is field 14, stime field 15.
  if (f.size() < 13) return 0;
  return static_cast<double>(std::stoll(f[11]) + std::stoll(f[12])) /
         static_cast<double>(::sysconf(_SC_CLK_TCK));
}

long procStatusKib(pid_t pid, const std::string& key) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind(key + ":", 0) == 0) return std::atol(line.c_str() + key.size() + 1);
  return -1;
}

// The send queue (unacknowledged + unsent bytes) of the daemon's socket to a client, from
// /proc/net/tcp; -1 when the connection is not there.
long daemonSendQueueBytes(unsigned short daemon_port, unsigned short client_port) {
  char local[32], remote[32];
  std::snprintf(local, sizeof local, "0100007F:%04X", daemon_port);
  std::snprintf(remote, sizeof remote, "0100007F:%04X", client_port);
  std::ifstream in("/proc/net/tcp");
  for (std::string line; std::getline(in, line);) {
    std::istringstream f(line);
    std::string sl, loc, rem, st, queues;
    f >> sl >> loc >> rem >> st >> queues;
    if (loc == local && rem == remote)
      return std::stol(queues.substr(0, queues.find(':')), nullptr, 16);
  }
  return -1;
}

// CLOCK_REALTIME - CLOCK_MONOTONIC, for the kernel's receive timestamps (realtime).
std::int64_t realtimeMinusMonotonicUs() {
  std::int64_t best_gap = INT64_MAX, offset = 0;
  for (int i = 0; i < 5; ++i) {
    timespec m1{}, rt{}, m2{};
    ::clock_gettime(CLOCK_MONOTONIC, &m1);
    ::clock_gettime(CLOCK_REALTIME, &rt);
    ::clock_gettime(CLOCK_MONOTONIC, &m2);
    const auto us = [](const timespec& t) { return t.tv_sec * 1000000LL + t.tv_nsec / 1000; };
    if (us(m2) - us(m1) < best_gap) {
      best_gap = us(m2) - us(m1);
      offset = us(rt) - (us(m1) + us(m2)) / 2;
    }
  }
  return offset;
}

double selfCpuS() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-6;
}

// /proc/pressure/cpu "some" total: microseconds during which some runnable task waited for a CPU
// (-1 without PSI).
long long cpuPressureUs() {
  std::ifstream in("/proc/pressure/cpu");
  for (std::string line; std::getline(in, line);) {
    const auto at = line.find("total=");
    if (line.rfind("some", 0) == 0 && at != std::string::npos)
      return std::atoll(line.c_str() + at + 6);
  }
  return -1;
}

std::string loadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  in >> a >> b >> c;
  return a + " " + b + " " + c;
}

// ------------------------------------------------------------------------------ clients
enum class Role { kWatcher, kStatus, kStuck };

// The stuck client: none, with the system's socket buffers (its kernel keeps taking data: the
// receive buffer grows up to net.ipv4.tcp_rmem's maximum), or with a small fixed SO_RCVBUF.
enum class Stuck { kNone, kDefaultBuffers, kSmallBuffer };

const char* stuckName(Stuck s) {
  switch (s) {
    case Stuck::kNone:
      return "none";
    case Stuck::kDefaultBuffers:
      return "default";
    case Stuck::kSmallBuffer:
      return "small";
  }
  return "?";
}

struct Conn {
  int fd = -1;
  Role role = Role::kWatcher;
  unsigned short local_port = 0;
  std::string partial;
  bool open = true;
  double closed_at_s = -1;  // by the daemon, from the start of the window
  // Watchers, inside the window:
  long received = 0;
  std::uint64_t first_seq = 0, last_seq = 0;
  long out_of_order = 0;
  std::int64_t max_latency_us = 0;
};

int connectTo(unsigned short port, unsigned short& local_port, int rcvbuf_bytes = 0) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error("socket failed");
  if (rcvbuf_bytes > 0) ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf_bytes, sizeof rcvbuf_bytes);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    throw std::runtime_error(std::string("connect to robocald: ") + std::strerror(errno));
  }
  sockaddr_in local{};
  socklen_t len = sizeof local;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&local), &len);
  local_port = ntohs(local.sin_port);
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  ::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof one);
  return fd;
}

void sendAll(int fd, const std::string& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::send(fd, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EAGAIN) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      continue;
    }
    if (n <= 0) throw std::runtime_error(std::string("send: ") + std::strerror(errno));
    done += static_cast<std::size_t>(n);
  }
}

template <typename Int>
bool numberAfter(std::string_view line, std::string_view key, Int& out) {
  const auto at = line.find(key);
  if (at == std::string_view::npos) return false;
  const char* begin = line.data() + at + key.size();
  return std::from_chars(begin, line.data() + line.size(), out).ec == std::errc();
}

// ------------------------------------------------------------------------------ one configuration
struct Result {
  int watchers = 0;
  Stuck stuck = Stuck::kNone;
  int stuck_rcvbuf_bytes = 0;
  double window_s = 0;
  long readings_daemon = 0;  // seq range seen in the window: lines the driver delivered
  double nominal_sent = 0;   // stream_hz x window
  std::int64_t p50_us = 0, p99_us = 0, p999_us = 0, max_us = 0;
  // Per reading, over the watchers: the first one to receive it and the last one (the spread
  // between them is the fan-out; the first mostly the hand-over between threads and processes).
  std::int64_t first_p50_us = 0, first_p99_us = 0, last_p50_us = 0, last_p99_us = 0;
  // The same, to the segment's arrival in the watcher's socket (SO_TIMESTAMPNS): the daemon and
  // the kernel, without the watcher's own wait for a CPU.
  std::int64_t arrival_p50_us = 0, arrival_p99_us = 0, arrival_max_us = 0;
  long samples = 0;
  long dropped_min = 0, dropped_max = 0, dropped_total = 0;
  long received_min = 0, received_max = 0;
  long watchers_disconnected = 0, out_of_order = 0;
  double daemon_cpu_pct = 0, cellsim_cpu_pct = 0, bench_cpu_pct = 0;
  long rss_start_kib = 0, rss_mid_kib = 0, rss_end_kib = 0, rss_min_kib = 0, rss_max_kib = 0,
       hwm_kib = 0;
  std::string load_before, load_after;
  double cpu_pressure_pct = -1;  // share of the window in which some task waited for a CPU
  // The stuck client, from the daemon's point of view.
  bool stuck_closed = false;
  double stuck_closed_after_s = -1;  // from its `watch`
  std::string stuck_reason;
  long stuck_kernel_received_bytes = -1;    // waiting unread in its receive queue, at the end
  long stuck_daemon_send_queue_bytes = -1;  // in the daemon's kernel send queue, at the end
  long status_clients_min = -1, status_clients_max = -1;
  int browsers = 0;
  long browser_received_min = 0, browser_received_max = 0;
  int browsers_closed = 0;
};

std::int64_t percentile(std::vector<std::int64_t>& v, double q) {
  if (v.empty()) return 0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

Result runConfig(const Options& o, int watchers, Stuck stuck_kind) {
  Result r;
  r.watchers = watchers;
  r.stuck = stuck_kind;
  const bool with_stuck = stuck_kind != Stuck::kNone;
  if (stuck_kind == Stuck::kSmallBuffer) r.stuck_rcvbuf_bytes = o.stuck_rcvbuf_bytes;
  const fs::path dir =
      fs::path(o.work_dir) / ("w" + std::to_string(watchers) + "-stuck-" + stuckName(stuck_kind));
  fs::create_directories(dir);
  std::error_code ec;
  fs::remove_all(dir / "data", ec);

  Child cellsim({o.cellsim, "--model", o.model, "--val-link", (dir / "val").string(), "--bar-link",
                 (dir / "bar").string(), "--control", (dir / "cellsim.sock").string(), "--bar-mode",
                 "streamed", "--stream-hz", std::to_string(o.stream_hz)},
                (dir / "cellsim.out").string(), (dir / "cellsim.log").string());
  cellsim.waitForLine("ready", 20);

  json config = {
      {"listen_address", "127.0.0.1"},
      {"port", 0},
      {"data_dir", (dir / "data").string()},
      {"model", o.model},
      {"cell", o.cell},
      {"max_clients", watchers + 8},
      {"drivers",
       {{"val", {{"serial", {{"path", (dir / "val").string()}}}}},
        {"bar", {{"serial", {{"path", (dir / "bar").string()}}}, {"mode", "streamed"}}}}}};
  if (o.browsers > 0) {
    config["web_port"] = 0;
    config["max_browsers"] = o.browsers + 4;
  }
  if (o.client_stall_s > 0) config["client_stall_s"] = o.client_stall_s;
  if (o.client_queue_max > 0) config["client_queue_max"] = o.client_queue_max;
  std::ofstream(dir / "robocald.json") << config.dump(2) << "\n";
  const std::string daemon_log = (dir / "robocald.log").string();
  Child daemon({o.robocald, "--config", (dir / "robocald.json").string()},
               (dir / "robocald.out").string(), daemon_log, o.daemon_nice);
  std::string listening = daemon.waitForLine("listening", 20);
  const auto port = static_cast<unsigned short>(std::stoi(listening.substr(listening.rfind(' '))));
  std::unique_ptr<robocal::bench::BrowserLoad> browsers;
  if (o.browsers > 0) {
    const std::string web = daemon.waitForLine("web ", 20);
    browsers = std::make_unique<robocal::bench::BrowserLoad>(
        static_cast<unsigned short>(std::stoi(web.substr(web.rfind(' ')))), o.browsers);
  }

  // Clients.
  std::vector<std::unique_ptr<Conn>> conns;
  const int ep = ::epoll_create1(EPOLL_CLOEXEC);
  const auto add = [&](Role role, bool watch, bool poll, int rcvbuf_bytes = 0) {
    auto c = std::make_unique<Conn>();
    c->role = role;
    c->fd = connectTo(port, c->local_port, rcvbuf_bytes);
    if (watch) sendAll(c->fd, "{\"cmd\":\"watch\"}\n");
    if (poll) {
      ::fcntl(c->fd, F_SETFL, ::fcntl(c->fd, F_GETFL) | O_NONBLOCK);
      epoll_event ev{};
      ev.events = EPOLLIN | EPOLLRDHUP;
      ev.data.ptr = c.get();
      ::epoll_ctl(ep, EPOLL_CTL_ADD, c->fd, &ev);
    }
    conns.push_back(std::move(c));
    return conns.back().get();
  };
  for (int i = 0; i < watchers; ++i) add(Role::kWatcher, true, true);
  Conn* status = add(Role::kStatus, false, true);
  Conn* stuck = nullptr;
  Clock::time_point stuck_watch_time;
  if (with_stuck) {
    stuck = add(Role::kStuck, true, false, r.stuck_rcvbuf_bytes);
    stuck_watch_time = Clock::now();
  }
  const std::string stuck_tag =
      stuck ? "(127.0.0.1:" + std::to_string(stuck->local_port) + ") closed: " : "";

  const auto t_connected = Clock::now();
  const auto window_start = t_connected + std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>(o.warmup_s));
  const auto window_mid = window_start + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(o.duration_s / 2));
  const auto window_end = window_start + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(o.duration_s));
  const std::int64_t window_start_us =
      std::chrono::duration_cast<std::chrono::microseconds>(window_start.time_since_epoch())
          .count();
  const std::int64_t window_end_us =
      std::chrono::duration_cast<std::chrono::microseconds>(window_end.time_since_epoch()).count();
  const auto grace = std::chrono::seconds(1);  // for the last readings of the window to arrive
  const auto stuck_deadline = window_end + std::chrono::duration_cast<Clock::duration>(
                                               std::chrono::duration<double>(o.stuck_wait_s));

  std::vector<std::int64_t> latencies_us, arrival_latencies_us;
  const std::int64_t realtime_minus_monotonic_us = realtimeMinusMonotonicUs();
  latencies_us.reserve(static_cast<std::size_t>(o.stream_hz * o.duration_s * watchers * 1.1) + 16);
  std::uint64_t seq_min = UINT64_MAX, seq_max = 0;
  std::map<std::uint64_t, std::pair<std::int64_t, std::int64_t>> first_last_us;  // by seq
  bool started = false, mid_sampled = false;
  double cpu0 = 0, cellsim_cpu0 = 0, self_cpu0 = 0;
  long long pressure0_us = -1;
  auto next_status = Clock::now();
  auto next_log_scan = Clock::now();
  auto next_rss = Clock::now();
  std::ifstream log_in;
  std::string log_partial;
  std::vector<char> buffer(1 << 16);
  std::vector<epoll_event> events(256);

  const auto scanLog = [&] {
    if (!stuck || r.stuck_closed) return;
    if (!log_in.is_open()) log_in.open(daemon_log);
    log_in.clear();
    std::string chunk((std::istreambuf_iterator<char>(log_in)), std::istreambuf_iterator<char>());
    log_partial += chunk;
    std::size_t nl;
    while ((nl = log_partial.find('\n')) != std::string::npos) {
      const std::string line = log_partial.substr(0, nl);
      log_partial.erase(0, nl + 1);
      const auto at = line.find(stuck_tag);
      if (at != std::string::npos) {
        r.stuck_closed = true;
        r.stuck_closed_after_s = sinceS(stuck_watch_time);
        r.stuck_reason = line.substr(at + stuck_tag.size());
      }
    }
  };

  while (true) {
    const auto now = Clock::now();
    if (!started && now >= window_start) {
      started = true;
      cpu0 = procCpuS(daemon.pid());
      cellsim_cpu0 = procCpuS(cellsim.pid());
      self_cpu0 = selfCpuS();
      pressure0_us = cpuPressureUs();
      r.rss_start_kib = r.rss_min_kib = r.rss_max_kib = procStatusKib(daemon.pid(), "VmRSS");
      r.load_before = loadAverage();
    }
    if (started && !mid_sampled && now >= window_mid) {
      mid_sampled = true;
      r.rss_mid_kib = procStatusKib(daemon.pid(), "VmRSS");
    }
    if (started && now < window_end && now >= next_rss) {
      next_rss = now + std::chrono::seconds(1);
      const long rss = procStatusKib(daemon.pid(), "VmRSS");
      r.rss_min_kib = std::min(r.rss_min_kib, rss);
      r.rss_max_kib = std::max(r.rss_max_kib, rss);
    }
    if (started && r.load_after.empty() && now >= window_end) {
      const double window_s = std::chrono::duration<double>(now - window_start).count();
      r.window_s = o.duration_s;
      r.daemon_cpu_pct = 100.0 * (procCpuS(daemon.pid()) - cpu0) / window_s;
      r.cellsim_cpu_pct = 100.0 * (procCpuS(cellsim.pid()) - cellsim_cpu0) / window_s;
      r.bench_cpu_pct = 100.0 * (selfCpuS() - self_cpu0) / window_s;
      r.rss_end_kib = procStatusKib(daemon.pid(), "VmRSS");
      r.hwm_kib = procStatusKib(daemon.pid(), "VmHWM");
      r.load_after = loadAverage();
      if (pressure0_us >= 0)
        r.cpu_pressure_pct =
            100.0 * static_cast<double>(cpuPressureUs() - pressure0_us) / (window_s * 1e6);
    }
    if (now >= window_end + grace && (!stuck || r.stuck_closed || now >= stuck_deadline)) break;
    if (!daemon.running()) throw std::runtime_error("robocald exited; see " + daemon_log);
    if (status->open && now >= next_status) {
      next_status = now + std::chrono::seconds(1);
      sendAll(status->fd, "{\"cmd\":\"status\"}\n");
    }
    if (now >= next_log_scan) {
      next_log_scan = now + std::chrono::milliseconds(100);
      scanLog();
    }

    const int n = ::epoll_wait(ep, events.data(), static_cast<int>(events.size()), 20);
    for (int i = 0; i < n; ++i) {
      Conn& c = *static_cast<Conn*>(events[static_cast<std::size_t>(i)].data.ptr);
      if (!c.open) continue;
      iovec iov{buffer.data(), buffer.size()};
      alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timespec))];
      msghdr msg{};
      msg.msg_iov = &iov;
      msg.msg_iovlen = 1;
      msg.msg_control = control;
      msg.msg_controllen = sizeof control;
      const ssize_t got = ::recvmsg(c.fd, &msg, 0);
      const std::int64_t received_us = nowUs();  // before any parsing
      std::int64_t arrived_us = -1;  // the kernel's time of the last segment read, monotonic
      for (cmsghdr* cm = CMSG_FIRSTHDR(&msg); cm; cm = CMSG_NXTHDR(&msg, cm))
        if (cm->cmsg_level == SOL_SOCKET && cm->cmsg_type == SCM_TIMESTAMPNS) {
          timespec ts{};
          std::memcpy(&ts, CMSG_DATA(cm), sizeof ts);
          arrived_us = ts.tv_sec * 1000000LL + ts.tv_nsec / 1000 - realtime_minus_monotonic_us;
        }
      if (got < 0 && (errno == EAGAIN || errno == EINTR)) continue;
      if (got <= 0) {
        c.open = false;
        c.closed_at_s = std::chrono::duration<double>(Clock::now() - window_start).count();
        ::epoll_ctl(ep, EPOLL_CTL_DEL, c.fd, nullptr);
        continue;
      }
      c.partial.append(buffer.data(), static_cast<std::size_t>(got));
      std::size_t begin = 0, nl;
      while ((nl = c.partial.find('\n', begin)) != std::string::npos) {
        const std::string_view line(c.partial.data() + begin, nl - begin);
        begin = nl + 1;
        if (c.role == Role::kStatus) {
          if (line.find("\"class\":\"STATUS\"") != std::string_view::npos) {
            long clients = -1;
            if (started && now < window_end && numberAfter(line, "\"clients\":", clients)) {
              if (r.status_clients_min < 0 || clients < r.status_clients_min)
                r.status_clients_min = clients;
              r.status_clients_max = std::max(r.status_clients_max, clients);
            }
          }
          continue;
        }
        if (line.rfind("{\"class\":\"BAR\"", 0) != 0) continue;
        std::uint64_t seq = 0;
        std::int64_t t_us = 0;
        if (!numberAfter(line, "\"seq\":", seq) || !numberAfter(line, "\"t_us\":", t_us)) continue;
        if (t_us < window_start_us || t_us >= window_end_us) continue;
        const std::int64_t latency_us = received_us - t_us;
        latencies_us.push_back(latency_us);
        if (arrived_us >= 0) arrival_latencies_us.push_back(arrived_us - t_us);
        c.max_latency_us = std::max(c.max_latency_us, latency_us);
        const auto [it, fresh] = first_last_us.try_emplace(seq, latency_us, latency_us);
        if (!fresh) {
          it->second.first = std::min(it->second.first, latency_us);
          it->second.second = std::max(it->second.second, latency_us);
        }
        if (c.received > 0 && seq <= c.last_seq) ++c.out_of_order;
        if (c.received == 0) c.first_seq = seq;
        c.last_seq = seq;
        ++c.received;
        seq_min = std::min(seq_min, seq);
        seq_max = std::max(seq_max, seq);
      }
      c.partial.erase(0, begin);
    }
  }
  scanLog();
  if (stuck) {
    int unread = 0;
    if (::ioctl(stuck->fd, FIONREAD, &unread) == 0) r.stuck_kernel_received_bytes = unread;
    r.stuck_daemon_send_queue_bytes = daemonSendQueueBytes(port, stuck->local_port);
  }

  // Results.
  r.readings_daemon = seq_max >= seq_min ? static_cast<long>(seq_max - seq_min + 1) : 0;
  r.nominal_sent = o.stream_hz * o.duration_s;
  r.samples = static_cast<long>(latencies_us.size());
  r.p50_us = percentile(latencies_us, 0.50);
  r.p99_us = percentile(latencies_us, 0.99);
  r.p999_us = percentile(latencies_us, 0.999);
  r.max_us = latencies_us.empty() ? 0 : *std::max_element(latencies_us.begin(), latencies_us.end());
  r.arrival_p50_us = percentile(arrival_latencies_us, 0.50);
  r.arrival_p99_us = percentile(arrival_latencies_us, 0.99);
  r.arrival_max_us = arrival_latencies_us.empty() ? 0
                                                  : *std::max_element(arrival_latencies_us.begin(),
                                                                      arrival_latencies_us.end());
  std::vector<std::int64_t> firsts_us, lasts_us;
  for (const auto& [seq, fl] : first_last_us) {
    firsts_us.push_back(fl.first);
    lasts_us.push_back(fl.second);
  }
  r.first_p50_us = percentile(firsts_us, 0.50);
  r.first_p99_us = percentile(firsts_us, 0.99);
  r.last_p50_us = percentile(lasts_us, 0.50);
  r.last_p99_us = percentile(lasts_us, 0.99);
  bool first = true;
  for (const auto& c : conns) {
    if (c->role != Role::kWatcher) continue;
    const long dropped = r.readings_daemon - c->received;
    if (first) {
      r.dropped_min = r.dropped_max = dropped;
      r.received_min = r.received_max = c->received;
      first = false;
    }
    r.dropped_min = std::min(r.dropped_min, dropped);
    r.dropped_max = std::max(r.dropped_max, dropped);
    r.received_min = std::min(r.received_min, c->received);
    r.received_max = std::max(r.received_max, c->received);
    r.dropped_total += dropped;
    r.out_of_order += c->out_of_order;
    if (!c->open) ++r.watchers_disconnected;
  }
  for (const auto& c : conns) ::close(c->fd);
  ::close(ep);
  if (browsers) {
    r.browsers = o.browsers;
    std::tie(r.browser_received_min, r.browser_received_max) = browsers->received();
    r.browsers_closed = browsers->closed();
    browsers.reset();
  }
  daemon.stop();
  cellsim.stop();
  return r;
}

// ------------------------------------------------------------------------------ output
json toJson(const Result& r) {
  return {{"watchers", r.watchers},
          {"stuck_client", stuckName(r.stuck)},
          {"stuck_rcvbuf_bytes", r.stuck_rcvbuf_bytes},
          {"window_s", r.window_s},
          {"readings_daemon", r.readings_daemon},
          {"readings_nominal", r.nominal_sent},
          {"latency_samples", r.samples},
          {"latency_p50_us", r.p50_us},
          {"latency_p99_us", r.p99_us},
          {"latency_p999_us", r.p999_us},
          {"latency_max_us", r.max_us},
          {"arrival_latency_p50_us", r.arrival_p50_us},
          {"arrival_latency_p99_us", r.arrival_p99_us},
          {"arrival_latency_max_us", r.arrival_max_us},
          {"first_watcher_latency_p50_us", r.first_p50_us},
          {"first_watcher_latency_p99_us", r.first_p99_us},
          {"last_watcher_latency_p50_us", r.last_p50_us},
          {"last_watcher_latency_p99_us", r.last_p99_us},
          {"dropped_per_watcher_min", r.dropped_min},
          {"dropped_per_watcher_max", r.dropped_max},
          {"dropped_total", r.dropped_total},
          {"received_per_watcher_min", r.received_min},
          {"received_per_watcher_max", r.received_max},
          {"watchers_disconnected", r.watchers_disconnected},
          {"out_of_order", r.out_of_order},
          {"daemon_cpu_pct", r.daemon_cpu_pct},
          {"cellsim_cpu_pct", r.cellsim_cpu_pct},
          {"bench_cpu_pct", r.bench_cpu_pct},
          {"rss_start_kib", r.rss_start_kib},
          {"rss_mid_kib", r.rss_mid_kib},
          {"rss_end_kib", r.rss_end_kib},
          {"rss_min_kib", r.rss_min_kib},
          {"rss_max_kib", r.rss_max_kib},
          {"rss_peak_kib", r.hwm_kib},
          {"status_clients_min", r.status_clients_min},
          {"status_clients_max", r.status_clients_max},
          {"load_average_before", r.load_before},
          {"load_average_after", r.load_after},
          {"cpu_pressure_pct", r.cpu_pressure_pct},
          {"stuck_closed", r.stuck_closed},
          {"stuck_closed_after_s", r.stuck_closed_after_s},
          {"stuck_reason", r.stuck_reason},
          {"stuck_kernel_received_bytes", r.stuck_kernel_received_bytes},
          {"stuck_daemon_send_queue_bytes", r.stuck_daemon_send_queue_bytes},
          {"browsers", r.browsers},
          {"browser_received_min", r.browser_received_min},
          {"browser_received_max", r.browser_received_max},
          {"browsers_closed", r.browsers_closed}};
}

void printTable(const Options& o, const std::vector<Result>& results) {
  std::printf(
      "robocal-bench-stream: %.0f readings/s, %.0f s window per configuration, %ld CPUs\n\n",
      o.stream_hz, o.duration_s, ::sysconf(_SC_NPROCESSORS_ONLN));
  std::printf("%-9s %-7s %8s %8s %8s %8s %8s %13s %15s %7s %7s %7s %27s\n", "watchers", "stuck",
              "readings", "samples", "p50_us", "p99_us", "max_us", "dropped/w", "received/w",
              "cpu_%", "cellsim", "bench", "rss_kib start/mid/end/peak");
  for (const auto& r : results) {
    char dropped[32], received[32], rss[64];
    std::snprintf(dropped, sizeof dropped, "%ld..%ld", r.dropped_min, r.dropped_max);
    std::snprintf(received, sizeof received, "%ld..%ld", r.received_min, r.received_max);
    std::snprintf(rss, sizeof rss, "%ld/%ld/%ld/%ld", r.rss_start_kib, r.rss_mid_kib, r.rss_end_kib,
                  r.hwm_kib);
    std::printf("%-9d %-7s %8ld %8ld %8lld %8lld %8lld %13s %15s %7.1f %7.1f %7.1f %27s\n",
                r.watchers, stuckName(r.stuck), r.readings_daemon, r.samples,
                static_cast<long long>(r.p50_us), static_cast<long long>(r.p99_us),
                static_cast<long long>(r.max_us), dropped, received, r.daemon_cpu_pct,
                r.cellsim_cpu_pct, r.bench_cpu_pct, rss);
  }
  std::printf("\n");
  for (const auto& r : results) {
    std::printf(
        "watchers=%d stuck=%s: %.0f readings sent (nominal), %ld read by the daemon; "
        "%ld watcher(s) disconnected, %ld out of order; load %s -> %s, CPU pressure %.0f %%\n",
        r.watchers, stuckName(r.stuck), r.nominal_sent, r.readings_daemon, r.watchers_disconnected,
        r.out_of_order, r.load_before.c_str(), r.load_after.c_str(), r.cpu_pressure_pct);
    std::printf(
        "  to the arrival in the watchers' sockets (kernel timestamp): p50/p99/max "
        "%lld/%lld/%lld us\n",
        static_cast<long long>(r.arrival_p50_us), static_cast<long long>(r.arrival_p99_us),
        static_cast<long long>(r.arrival_max_us));
    std::printf(
        "  per reading, first watcher p50/p99 %lld/%lld us, last watcher p50/p99 %lld/%lld "
        "us; p99.9 over all %lld us\n",
        static_cast<long long>(r.first_p50_us), static_cast<long long>(r.first_p99_us),
        static_cast<long long>(r.last_p50_us), static_cast<long long>(r.last_p99_us),
        static_cast<long long>(r.p999_us));
    if (r.browsers > 0)
      std::printf("  %d browsers (WebSocket watchers): %ld..%ld messages each, %d closed\n",
                  r.browsers, r.browser_received_min, r.browser_received_max, r.browsers_closed);
    if (r.stuck == Stuck::kNone) continue;
    char buffers[64] = "system default buffers";
    if (r.stuck == Stuck::kSmallBuffer)
      std::snprintf(buffers, sizeof buffers, "SO_RCVBUF %d", r.stuck_rcvbuf_bytes);
    if (r.stuck_closed)
      std::printf("  stuck client (%s): closed by the daemon %.1f s after its watch: %s\n", buffers,
                  r.stuck_closed_after_s, r.stuck_reason.c_str());
    else
      std::printf(
          "  stuck client (%s): still connected at the end (%.0f s after its watch); "
          "its kernel holds %ld unread bytes, the daemon's send queue %ld\n",
          buffers, o.warmup_s + o.duration_s + std::max(1.0, o.stuck_wait_s),
          r.stuck_kernel_received_bytes, r.stuck_daemon_send_queue_bytes);
  }
}

std::string besideSelf(const std::string& relative) {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return (self.parent_path() / relative).lexically_normal().string();
}

[[noreturn]] void usage(int code) {
  std::fprintf(code ? stderr : stdout,
               "usage: robocal-bench-stream [--watchers 1,16,64] [--no-compare] [--duration-s S]\n"
               "  [--warmup-s S] [--stream-hz F] [--stuck-rcvbuf-bytes N] [--stuck-wait-s S]\n"
               "  [--client-stall-s S] [--client-queue-max N] [--daemon-nice N]\n"
               "  [--bench-slice-us U] [--cellsim PATH] [--robocald PATH] [--model FILE]\n"
               "  [--cell FILE] [--work-dir DIR] [--json]\n");
  std::exit(code);
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  o.cellsim = besideSelf("../sim/cellsim/robocal-cellsim");
  o.robocald = besideSelf("../daemon/robocald");
  o.model = std::string(ROBOCAL_SOURCE_DIR) + "/config/puma560.json";
  o.cell = std::string(ROBOCAL_SOURCE_DIR) + "/config/cell.json";
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      const auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
        return argv[++i];
      };
      if (a == "--watchers") {
        o.watchers.clear();
        std::istringstream in(value());
        for (std::string s; std::getline(in, s, ',');) o.watchers.push_back(std::stoi(s));
      } else if (a == "--no-compare") {
        o.compare_without_stuck = false;
      } else if (a == "--duration-s") {
        o.duration_s = std::stod(value());
      } else if (a == "--warmup-s") {
        o.warmup_s = std::stod(value());
      } else if (a == "--stream-hz") {
        o.stream_hz = std::stod(value());
      } else if (a == "--stuck-wait-s") {
        o.stuck_wait_s = std::stod(value());
      } else if (a == "--stuck-rcvbuf-bytes") {
        o.stuck_rcvbuf_bytes = std::stoi(value());
      } else if (a == "--bench-slice-us") {
        o.bench_slice_us = std::stoi(value());
      } else if (a == "--daemon-nice") {
        o.daemon_nice = std::stoi(value());
      } else if (a == "--client-stall-s") {
        o.client_stall_s = std::stod(value());
      } else if (a == "--client-queue-max") {
        o.client_queue_max = std::stol(value());
      } else if (a == "--cellsim") {
        o.cellsim = value();
      } else if (a == "--robocald") {
        o.robocald = value();
      } else if (a == "--model") {
        o.model = value();
      } else if (a == "--cell") {
        o.cell = value();
      } else if (a == "--work-dir") {
        o.work_dir = value();
      } else if (a == "--browsers") {
        o.browsers = std::stoi(value());
      } else if (a == "--json") {
        o.json_output = true;
      } else if (a == "--help" || a == "-h") {
        usage(0);
      } else {
        throw std::invalid_argument("unknown option " + a);
      }
    }
    if (o.watchers.empty() || o.duration_s <= 0 || o.stream_hz <= 0)
      throw std::invalid_argument("--watchers, --duration-s and --stream-hz must be positive");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "robocal-bench-stream: %s\n", e.what());
    usage(2);
  }
  ::signal(SIGPIPE, SIG_IGN);
  if (o.bench_slice_us > 0 && !setSliceUs(o.bench_slice_us))
    std::fprintf(stderr, "robocal-bench-stream: no time slice: %s\n", std::strerror(errno));
  bool remove_work_dir = false;
  if (o.work_dir.empty()) {
    char tmpl[] = "/tmp/robocal-bench-stream-XXXXXX";
    if (!::mkdtemp(tmpl)) {
      std::fprintf(stderr, "robocal-bench-stream: mkdtemp failed\n");
      return 1;
    }
    o.work_dir = tmpl;
    remove_work_dir = true;
  }
  o.model = fs::absolute(o.model).string();
  o.cell = fs::absolute(o.cell).string();

  const int largest = *std::max_element(o.watchers.begin(), o.watchers.end());
  std::vector<std::pair<int, Stuck>> configs;
  for (int n : o.watchers) configs.emplace_back(n, Stuck::kDefaultBuffers);
  if (o.compare_without_stuck) configs.emplace_back(largest, Stuck::kNone);
  if (o.stuck_rcvbuf_bytes > 0) configs.emplace_back(largest, Stuck::kSmallBuffer);

  std::vector<Result> results;
  int status = 0;
  try {
    for (const auto& [n, stuck] : configs) {
      if (!o.json_output)
        std::fprintf(stderr, "robocal-bench-stream: %d watcher(s), stuck client: %s, %.0f s...\n",
                     n, stuckName(stuck), o.warmup_s + o.duration_s);
      results.push_back(runConfig(o, n, stuck));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "robocal-bench-stream: %s (work dir %s kept)\n", e.what(),
                 o.work_dir.c_str());
    remove_work_dir = false;
    status = 1;
  }
  if (o.json_output) {
    json out = {{"stream_hz", o.stream_hz},
                {"bench_slice_us", o.bench_slice_us},
                {"duration_s", o.duration_s},
                {"warmup_s", o.warmup_s},
                {"cpus", ::sysconf(_SC_NPROCESSORS_ONLN)},
                {"configurations", json::array()}};
    for (const auto& r : results) out["configurations"].push_back(toJson(r));
    std::printf("%s\n", out.dump(2).c_str());
  } else {
    printTable(o, results);
  }
  if (remove_work_dir) {
    std::error_code ec;
    fs::remove_all(o.work_dir, ec);
  }
  return status;
}
