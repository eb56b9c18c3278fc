#include <robocal/daemon/config.hpp>

#include <robocal/drivers/errors.hpp>
#include <robocal/formats/error.hpp>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>

namespace robocal::daemon {
namespace {

using json = nlohmann::json;

class Reader {
 public:
  Reader(const json& obj, std::string source, std::string base_dir)
      : obj_(obj), source_(std::move(source)), base_(std::move(base_dir)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
    throw ConfigError(source_ + ": " + key + ": " + problem);
  }
  const json* find(const std::string& key) {
    seen_.insert(key);
    const auto it = obj_.find(key);
    return it == obj_.end() ? nullptr : &*it;
  }
  void string(const std::string& key, std::string& out) {
    if (const json* v = find(key)) {
      if (!v->is_string()) fail(key, std::string("expected a string, got ") + v->type_name());
      out = v->get<std::string>();
    }
  }
  void path(const std::string& key, std::string& out) {
    string(key, out);
    if (!out.empty() && !std::filesystem::path(out).is_absolute())
      out = (std::filesystem::path(base_) / out).lexically_normal().string();
  }
  void number(const std::string& key, double& out, double lo, double hi) {
    if (const json* v = find(key)) {
      if (!v->is_number()) fail(key, std::string("expected a number, got ") + v->type_name());
      out = v->get<double>();
      if (!(out >= lo && out <= hi))
        fail(key, "must be from " + json(lo).dump() + " to " + json(hi).dump());
    }
  }
  template <typename Int>
  void integer(const std::string& key, Int& out, long lo, long hi) {
    if (const json* v = find(key)) {
      if (!v->is_number_integer())
        fail(key, std::string("expected a whole number, got ") + v->type_name());
      const long value = v->get<long>();
      if (value < lo || value > hi)
        fail(key, "must be from " + std::to_string(lo) + " to " + std::to_string(hi));
      out = static_cast<Int>(value);
    }
  }
  void boolean(const std::string& key, bool& out) {
    if (const json* v = find(key)) {
      if (!v->is_boolean()) fail(key, std::string("expected true or false, got ") + v->type_name());
      out = v->get<bool>();
    }
  }
  void rejectUnknown() const {
    for (const auto& [key, value] : obj_.items())
      if (!seen_.count(key)) fail(key, "unknown key");
  }

 private:
  const json& obj_;
  std::string source_, base_;
  std::set<std::string> seen_;
};

}  // namespace

DaemonConfig daemonConfigFromJson(const json& root, const std::string& source,
                                  const std::string& base_dir) {
  if (!root.is_object()) throw ConfigError(source + ": expected a JSON object");
  DaemonConfig c;
  Reader r(root, source, base_dir);
  r.string("listen_address", c.listen_address);
  r.integer("port", c.port, 0, 65535);  // 0: any free port (printed at start)
  r.path("data_dir", c.data_dir);
  r.path("token_file", c.token_file);
  r.path("model", c.model);
  r.path("cell", c.cell);
  r.path("plan", c.plan);
  r.number("settle_s", c.settle_s, 0, 60);
  r.number("bar_window_s", c.bar_window_s, 0, 10);
  r.number("bar_soft_limit_mm", c.bar_soft_limit_mm, 0.01, 100);
  r.number("bar_hard_limit_mm", c.bar_hard_limit_mm, 0.01, 100);
  r.boolean("centering", c.centering);
  r.number("connection_check_mm", c.connection_check_mm, 0, 5);
  r.number("detached_change_mm", c.detached_change_mm, 0.01, 100);
  r.integer("max_clients", c.max_clients, 1, 10000);
  r.integer("max_line_bytes", c.max_line_bytes, 256, 16 * 1024 * 1024);
  r.integer("client_queue_max", c.client_queue_max, 16, 1000000);
  r.number("client_stall_s", c.client_stall_s, 0.1, 3600);
  r.number("request_timeout_s", c.request_timeout_s, 0.1, 3600);
  r.path("log_file", c.log_file);
  r.string("log_level", c.log_level);
  r.number("watchdog_interval_s", c.watchdog_interval_s, 0, 3600);
  if (const json* d = r.find("drivers")) {
    try {
      c.drivers = drivers::driversConfigFromJson(*d, source + ": drivers");
    } catch (const drivers::ConfigError& e) {
      throw ConfigError(e.what());
    }
  }
  r.rejectUnknown();
  if (c.model.empty()) r.fail("model", "missing: the nominal model file is required");
  if (c.cell.empty() && c.plan.empty())
    r.fail("cell", "missing: a cell file (or a fixed plan) is required");
  if (c.bar_soft_limit_mm >= c.bar_hard_limit_mm)
    r.fail("bar_soft_limit_mm", "must be below bar_hard_limit_mm");
  static const std::set<std::string> levels = {"trace", "debug", "info", "warn", "error"};
  if (!levels.count(c.log_level)) r.fail("log_level", "one of trace, debug, info, warn, error");
  if (c.token_file.empty()) c.token_file = (std::filesystem::path(c.data_dir) / "token").string();
  return c;
}

DaemonConfig loadDaemonConfig(const std::string& path) {
  const std::string text = readTextFile(path);
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {
    throw ConfigError(path + ": not valid JSON: " + e.what());
  }
  const std::string base = std::filesystem::absolute(path).parent_path().string();
  return daemonConfigFromJson(root, path, base);
}

}  // namespace robocal::daemon
