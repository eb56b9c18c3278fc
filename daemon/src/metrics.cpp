#include <robocal/daemon/metrics.hpp>

#include <robocal/proto/protocol.hpp>

#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

namespace robocal::daemon {

using json = nlohmann::json;

namespace {

// A label value as the text format wants it: backslash, quote and newline escaped.
std::string labelValue(const std::string& v) {
  std::string out;
  for (char c : v) {
    if (c == '\\' || c == '"')
      out += '\\', out += c;
    else if (c == '\n')
      out += "\\n";
    else
      out += c;
  }
  return out;
}

// Prometheus asks for base units: lengths are exposed in meters (the protocol's JSON keeps mm).
constexpr double kMetersPerMm = 1e-3;

std::string number(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "+Inf" : "-Inf";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

class Exposition {
 public:
  // One metric family: its HELP and TYPE lines, once.
  Exposition& family(const std::string& name, const char* type, const std::string& help) {
    name_ = name;
    out_ += "# HELP " + name + " " + help + "\n# TYPE " + name + " " + type + "\n";
    return *this;
  }
  using Labels = std::vector<std::pair<std::string, std::string>>;
  Exposition& sample(double value, const Labels& labels = {}) {
    out_ += name_;
    for (size_t k = 0; k < labels.size(); ++k)
      out_ += (k ? "," : "{") + labels[k].first + "=\"" + labelValue(labels[k].second) + "\"" +
              (k + 1 == labels.size() ? "}" : "");
    out_ += " " + number(value) + "\n";
    return *this;
  }
  Exposition& sample(double value, const std::string& label, const std::string& v) {
    return sample(value, Labels{{label, v}});
  }
  Exposition& counts(const std::map<std::string, long>& m, const std::string& label,
                     const Labels& more = {}) {
    for (const auto& [k, n] : m) {
      Labels labels = more;
      labels.emplace_back(label, k);
      sample(static_cast<double>(n), labels);
    }
    return *this;
  }
  std::string str() const { return out_; }

 private:
  std::string name_;
  std::string out_;
};

double numberOr(const json& o, const char* key, double fallback) {
  const auto it = o.find(key);
  return it != o.end() && it->is_number() ? it->get<double>() : fallback;
}

}  // namespace

void Metrics::observe(const json& object) {
  if (!object.is_object()) return;
  const std::string cls = object.value("class", "");
  if (cls == "BAR") {
    ++bar_lines_[object.value("kind", "unknown")];
  } else if (cls == "SAMPLE") {
    ++samples_;
  } else if (cls == "STATE") {
    const std::string to = object.value("to", "");
    if (to == "paused" || to == "interrupted" || to == "error") ++stops_[to];
  } else if (cls == "EVENT") {
    const std::string event = object.value("event", "");
    ++events_[event];
    if (event == "link_faults")
      for (const auto& [key, value] : object.items())
        if (value.is_number_integer() && key != "shell") link_faults_[key] += value.get<long>();
  }
}

std::string Metrics::text(const json& status, const json& result, const Clients& clients) const {
  Exposition e;
  const std::string state = status.value("state", "");
  e.family("robocal_run_state", "gauge", "1 for the run's current state, 0 for the others.");
  // Every state the protocol spells (RunState, kIdle to kError), by its wire name.
  for (int k = 0; k <= static_cast<int>(proto::RunState::kError); ++k) {
    const std::string name = proto::runStateName(static_cast<proto::RunState>(k));
    e.sample(state == name ? 1 : 0, "state", name);
  }
  e.family("robocal_points_done", "gauge", "Data points measured in the current run.")
      .sample(numberOr(status, "points_done", 0));
  e.family("robocal_plan_points", "gauge", "Data points in the current run's plan.")
      .sample(numberOr(status, "points_total", 0));
  e.family("robocal_shell", "gauge", "The shell the run is on (0: none).")
      .sample(numberOr(status, "shell", 0));
  e.family("robocal_eta_seconds", "gauge", "Robot time left in the run, seconds.")
      .sample(numberOr(status, "eta_s", 0));
  e.family("robocal_samples_total", "counter", "Samples written since the daemon started.")
      .sample(static_cast<double>(samples_));
  e.family("robocal_bar_attached", "gauge", "1 while the bar may be on the robot.")
      .sample(status.value("bar_attached", false) ? 1 : 0);
  const json bar = status.value("bar", json());
  if (bar.is_object() && bar.contains("deflection_mm"))
    e.family("robocal_bar_deflection_meters", "gauge", "The latest ball-bar reading, meters.")
        .sample(kMetersPerMm * numberOr(bar, "deflection_mm", NAN));
  e.family("robocal_bar_lines_total", "counter",
           "Ball-bar reader lines since the daemon started, by kind.")
      .counts(bar_lines_, "kind");
  const auto over = bar_lines_.find("over_range");
  e.family("robocal_bar_over_range_total", "counter", "Ball-bar readings past its range.")
      .sample(over == bar_lines_.end() ? 0 : static_cast<double>(over->second));
  e.family("robocal_faults_total", "counter",
           "Serial faults the drivers absorbed (garbled lines, timeouts, retries), by kind.")
      .counts(link_faults_, "kind");
  e.family("robocal_run_stops_total", "counter",
           "Runs stopped by a fault or an operator, by the state they went to.")
      .counts(stops_, "state");
  e.family("robocal_events_total", "counter", "Run events (re-centring, re-plans, ...), by event.")
      .counts(events_, "event");
  const json devices = status.value("devices", json::object());
  e.family("robocal_device_connected", "gauge", "1 while the device's serial link is up.")
      .sample(devices.value("val", false) ? 1 : 0, "device", "val")
      .sample(devices.value("bar", false) ? 1 : 0, "device", "bar");
  e.family("robocal_clients", "gauge", "Connected clients, by transport.")
      .sample(clients.tcp, "transport", "tcp")
      .sample(clients.web, "transport", "web");
  const json counts = status.value("client_counts", json::object());
  std::map<std::string, long> tcp_events;
  for (const auto& [k, v] : counts.items())
    if (v.is_number()) tcp_events[k] = v.get<long>();
  const std::map<std::string, long> web_events = {
      {"refused", clients.web_counts.refused},
      {"stalled", clients.web_counts.stalled},
      {"dropped_lines", clients.web_counts.dropped_lines},
      {"http_refused", clients.web_counts.http_refused}};
  e.family("robocal_client_events_total", "counter",
           "Clients refused, closed as stuck or timed out, and readings dropped for slow ones.")
      .counts(tcp_events, "kind", {{"transport", "tcp"}})
      .counts(web_events, "kind", {{"transport", "web"}});
  if (result.value("available", true) && result.contains("rms_mm")) {
    e.family("robocal_fit_rms_meters", "gauge", "The latest fit's residual RMS, meters.")
        .sample(kMetersPerMm * numberOr(result, "rms_mm", NAN));
    e.family("robocal_fit_samples", "gauge", "Samples in the latest fit.")
        .sample(numberOr(result, "n", 0));
    if (result.contains("validation_rms_mm"))
      e.family("robocal_validation_rms_meters", "gauge",
               "The latest fit's residual RMS on samples it did not fit, meters.")
          .sample(kMetersPerMm * numberOr(result, "validation_rms_mm", NAN));
    const json wv = result.value("work_volume", json::object());
    if (wv.is_object() && wv.contains("predicted_position_error_mm"))
      e.family("robocal_work_volume_error_meters", "gauge",
               "Predicted RMS tool position error over the work volume, meters.")
          .sample(kMetersPerMm * numberOr(wv["predicted_position_error_mm"], "rms", NAN));
  }
  return e.str();
}

}  // namespace robocal::daemon
