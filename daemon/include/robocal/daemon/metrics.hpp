// The plant's view of robocald (/metrics, docs/console.md): counters kept from every object the
// daemon publishes, fed on the event loop, and the Prometheus text format (version 0.0.4) made
// from them with the current STATUS and RESULT. Pure: no I/O, no clock.
#pragma once

#include <robocal/daemon/web_server.hpp>

#include <nlohmann/json.hpp>

#include <map>
#include <string>

namespace robocal::daemon {

class Metrics {
 public:
  // Every object the daemon publishes to watchers (BAR, SAMPLE, STATE, EVENT, ...).
  void observe(const nlohmann::json& object);
  struct Clients {
    int tcp = 0, web = 0;  // connected now
    WebCounts web_counts;  // browsers refused, closed as stuck, readings dropped
  };
  // The exposition: `status` a STATUS object (its client_counts are the TCP side's), `result` a
  // RESULT object (or one with "available": false).
  std::string text(const nlohmann::json& status, const nlohmann::json& result,
                   const Clients& clients) const;

 private:
  std::map<std::string, long> bar_lines_;    // BAR lines by kind
  std::map<std::string, long> link_faults_;  // the drivers' absorbed faults, by counter
  std::map<std::string, long> events_;       // EVENT objects by event
  std::map<std::string, long> stops_;        // STATE changes into paused, interrupted, error
  long samples_ = 0;
};

}  // namespace robocal::daemon
