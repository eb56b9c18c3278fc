#include <robocal/daemon/config.hpp>

#include <robocal/drivers/errors.hpp>
#include <robocal/formats/error.hpp>
#include <robocal/jsonread/strict_json.hpp>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>

namespace robocal::daemon {
namespace {

using json = nlohmann::json;

// A relative path in the config is relative to the config file's folder.
void getPath(jsonread::Object<ConfigError>& r, const std::string& key, const std::string& base,
             std::string& out) {
  r.get(key, out);
  if (!out.empty() && !std::filesystem::path(out).is_absolute())
    out = (std::filesystem::path(base) / out).lexically_normal().string();
}

}  // namespace

DaemonConfig daemonConfigFromJson(const json& root, const std::string& source,
                                  const std::string& base_dir) {
  DaemonConfig c;
  jsonread::Object<ConfigError> r(jsonread::Reader<ConfigError>(source), root, "");
  r.get("listen_address", c.listen_address);
  r.get("port", c.port, 0, 65535);  // 0: any free port (printed at start)
  getPath(r, "data_dir", base_dir, c.data_dir);
  getPath(r, "token_file", base_dir, c.token_file);
  getPath(r, "model", base_dir, c.model);
  getPath(r, "cell", base_dir, c.cell);
  getPath(r, "plan", base_dir, c.plan);
  r.get("settle_s", c.settle_s, 0, 60);
  r.get("bar_window_s", c.bar_window_s, 0, 10);
  r.get("dwell_mode", c.dwell_mode);
  r.get("adaptive_window_s", c.adaptive_window_s, 0.01, 10);
  r.get("bar_noise_mm", c.bar_noise_mm, 0, 1);
  r.get("adaptive_audit_every", c.adaptive_audit_every, 0, 100000);
  r.get("bar_soft_limit_mm", c.bar_soft_limit_mm, 0.01, 100);
  r.get("bar_hard_limit_mm", c.bar_hard_limit_mm, 0.01, 100);
  r.get("centering", c.centering);
  r.get("connection_check_mm", c.connection_check_mm, 0, 5);
  r.get("detached_change_mm", c.detached_change_mm, 0.01, 100);
  r.get("web_address", c.web_address);
  r.get("web_port", c.web_port, -1, 65535);
  r.get("max_browsers", c.max_browsers, 1, 1000);
  r.get("web_allowed_origins", c.web_allowed_origins);
  r.get("max_clients", c.max_clients, 1, 10000);
  r.get("max_line_bytes", c.max_line_bytes, 256, 16 * 1024 * 1024);
  r.get("client_queue_max", c.client_queue_max, 16, 1000000);
  r.get("client_stall_s", c.client_stall_s, 0.1, 3600);
  r.get("request_timeout_s", c.request_timeout_s, 0.1, 3600);
  getPath(r, "log_file", base_dir, c.log_file);
  r.get("log_level", c.log_level);
  r.get("watchdog_interval_s", c.watchdog_interval_s, 0, 3600);
  r.get("check_warn_ratio", c.check_warn_ratio, 1.0, 100);
  r.get("check_fail_ratio", c.check_fail_ratio, 1.0, 100);
  if (const json* d = r.find("drivers")) {
    try {
      c.drivers = drivers::driversConfigFromJson(*d, source + ": drivers");
    } catch (const drivers::ConfigError& e) {
      throw ConfigError(e.what());
    }
  }
  r.finish();
  if (c.model.empty()) r.fail("model", "missing: the nominal model file is required");
  if (c.cell.empty() && c.plan.empty())
    r.fail("cell", "missing: a cell file (or a fixed plan) is required");
  if (c.web_port > 0 && c.web_port == c.port && c.web_address == c.listen_address)
    r.fail("web_port", "must differ from port (" + std::to_string(c.port) + ")");
  if (c.bar_soft_limit_mm >= c.bar_hard_limit_mm)
    r.fail("bar_soft_limit_mm", "must be below bar_hard_limit_mm");
  if (c.check_warn_ratio > c.check_fail_ratio)
    r.fail("check_warn_ratio", "must not be above check_fail_ratio");
  if (c.dwell_mode != "fixed" && c.dwell_mode != "adaptive")
    r.fail("dwell_mode", "fixed or adaptive");
  if (c.dwell_mode == "adaptive" && c.bar_noise_mm <= 0 && c.connection_check_mm <= 0)
    r.fail("bar_noise_mm",
           "required with dwell_mode adaptive when connection_check_mm is 0 (the connection "
           "check measures the noise otherwise): the bar reader's noise (1 sigma, mm), as "
           "measured with the robot still (docs/settling.md)");
  if (c.dwell_mode == "adaptive" && c.adaptive_window_s >= c.settle_s)
    r.fail("adaptive_window_s", "must be below settle_s, or the adaptive dwell never ends early");
  static const std::set<std::string> levels = {"trace", "debug", "info", "warn", "error"};
  if (!levels.count(c.log_level)) r.fail("log_level", "one of trace, debug, info, warn, error");
  if (c.token_file.empty()) c.token_file = (std::filesystem::path(c.data_dir) / "token").string();
  return c;
}

DaemonConfig loadDaemonConfig(const std::string& path) {
  const std::string text = readTextFile(path);
  const json root =
      jsonread::parseText<ConfigError>(text, path, "robocald's config (docs/robocald.md)");
  const std::string base = std::filesystem::absolute(path).parent_path().string();
  return daemonConfigFromJson(root, path, base);
}

}  // namespace robocal::daemon
