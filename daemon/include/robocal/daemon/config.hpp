// robocald's configuration file (docs/robocald.md). Every key is validated at start: unknown
// keys, wrong types and out-of-range values are refused with the key's name.
#pragma once

#include <robocal/drivers/config.hpp>
#include <robocal/solver/health.hpp>

#include <stdexcept>
#include <string>
#include <vector>

namespace robocal::daemon {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct DaemonConfig {
  std::string listen_address = "127.0.0.1";
  int port = 7687;
  std::string data_dir = "/var/lib/robocald";  // runs/<id>/ below it
  std::string token_file;                      // default: <data_dir>/token (mode 0600)
  std::string model;                           // nominal model file (required)
  std::string cell;                            // cell file for planning (required)
  std::string plan;                            // a fixed plan file to run by default (optional)
  double settle_s = 2.0;                       // dwell at each data point before recording
  double bar_window_s = 0.2;                   // bar readings averaged after the dwell
  // The dwell (docs/settling.md): "fixed" waits settle_s; "adaptive" ends it as soon as the bar's
  // readings over the last adaptive_window_s are steady (trend and spread at the bar's noise),
  // and never later than settle_s.
  std::string dwell_mode = "fixed";
  double adaptive_window_s = 0.5;
  // The bar reader's noise, 1 sigma; 0: measured by each connection check (its windows, read
  // with the robot still after settle_s).
  double bar_noise_mm = 0;
  // Every Nth adaptive dwell whose readings were steady goes on to settle_s, and the two readings
  // are compared (the first is audited too); 0: none. A second failed audit: fixed dwell.
  int adaptive_audit_every = 10;
  double bar_soft_limit_mm = 1.0;  // |deflection| past this during a move: stop and re-centre
  double bar_hard_limit_mm = 1.8;  // past this: stop the robot and pause the run
  bool centering = true;           // refine the model and re-plan while a shell runs
  // After each connect: the ball moves this far out and in along the bar, and the reading must
  // follow (a free bar or a wrong chuck does not); 0 turns the check off. Capped at 0.4 x the
  // soft limit.
  double connection_check_mm = 0.5;
  // A reading that changes this much while the robot moves with the bar believed detached stops
  // the robot: the bar is still attached.
  double detached_change_mm = 0.25;
  // The browser console and /metrics (docs/console.md): its own port, -1 (the default when the
  // key is absent) for none, 0 for any free one (printed at start as "web ADDRESS PORT").
  std::string web_address = "127.0.0.1";
  int web_port = -1;
  int max_browsers = 32;
  std::vector<std::string> web_allowed_origins;  // besides the page's own
  int max_clients = 64;
  std::size_t max_line_bytes = 16 * 1024;
  std::size_t client_queue_max = 4096;  // messages queued to one client; past it readings drop
  double client_stall_s = 5.0;          // a client that takes nothing this long is disconnected
  double request_timeout_s = 10.0;      // a request line unfinished this long: disconnected
  std::string log_file;                 // optional, besides stderr (journald)
  std::string log_level = "info";       // trace, debug, info, warn, error
  double watchdog_interval_s = 0;       // 0: from $WATCHDOG_USEC when systemd sets it
  // The health check's verdict (docs/health-check.md): a named change fails; with none, the
  // check's bar RMS under the active model over the level its calibration reached, from
  // warn_ratio warn, from fail_ratio fail (HealthOptions).
  double check_warn_ratio = HealthOptions{}.warn_ratio;
  double check_fail_ratio = HealthOptions{}.fail_ratio;
  drivers::DriversConfig drivers;
};

// Parses the file; relative paths in it are taken relative to the file's folder.
DaemonConfig loadDaemonConfig(const std::string& path);
DaemonConfig daemonConfigFromJson(const nlohmann::json& json, const std::string& source,
                                  const std::string& base_dir);

}  // namespace robocal::daemon
