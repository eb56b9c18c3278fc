// robocal run-timing RUN_DIR: the dwell timing of a daemon run, from the "timing" events robocald
// logs per data point in the run's events.jsonl (docs/reliability.md, dwell timing).
#include "args.hpp"

#include <robocal/formats/error.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

namespace robocal::cli {
namespace {

using json = nlohmann::json;

constexpr const char* kHelp = R"(usage: robocal run-timing RUN_DIR [--json]

Summarises the dwell timing robocald logged for each data point of a run (RUN_DIR/events.jsonl,
"timing" events): the achieved settle time (motion complete to the bar window's start) against
the configured settle_s, the controller's WHERE within the window, and the time from motion
complete to the sample fsynced on disk. Prints min, p50, p99 and max of each (ms), and how the
points dwelt: adaptive or fixed, ended early by steady readings, the adaptive dwell's audits and
whether they turned it off, and the bar's noise each connection check measured
(docs/settling.md). Exits 1 when the run has no timing events.

  --json    one JSON object instead of the table
)";

// How the points dwelt (docs/settling.md), from the timing, dwell_audit, adaptive_dwell_off and
// connection_check events.
struct DwellSummary {
  int adaptive = 0, fixed = 0, ended_early = 0, audits = 0, audits_failed = 0;
  std::vector<std::string> turned_off;  // the reasons, one a turning off
  std::vector<double> still_noise_mm;   // one a connection check

  void add(const json& ev) {
    const std::string name = ev.value("event", "");
    // Every field read before anything is counted: a damaged event counts nowhere.
    if (name == "timing") {
      const bool is_adaptive = ev.value("dwell_mode", "fixed") == "adaptive";
      const bool steady = ev.value("steady", false);
      (is_adaptive ? adaptive : fixed) += 1;
      ended_early += steady;
    } else if (name == "dwell_audit") {
      const bool passed = ev.value("passed", true);
      ++audits;
      audits_failed += !passed;
    } else if (name == "adaptive_dwell_off") {
      turned_off.push_back(ev.value("reason", ""));
    } else if (name == "connection_check" && ev.contains("still_noise_mm")) {
      still_noise_mm.push_back(ev.value("still_noise_mm", 0.0));
    }
  }
  json toJson() const {
    return {{"adaptive", adaptive},
            {"fixed", fixed},
            {"ended_early", ended_early},
            {"audits", audits},
            {"audits_failed", audits_failed},
            {"turned_off", turned_off},
            {"still_noise_mm", still_noise_mm}};
  }
  void print() const {
    std::printf(
        "dwell: %d adaptive (%d ended early by steady readings), %d fixed; %d audit%s, %d "
        "failed\n",
        adaptive, ended_early, fixed, audits, audits == 1 ? "" : "s", audits_failed);
    if (!still_noise_mm.empty()) {
      std::printf("bar noise measured by the connection checks (mm):");
      for (double n : still_noise_mm) std::printf(" %.5f", n);
      std::printf("\n");
    }
    for (const std::string& why : turned_off)
      std::printf("the adaptive dwell was turned off: %s\n", why.c_str());
  }
};

// Nearest-rank percentile of sorted values.
double percentile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return 0;
  const auto rank = static_cast<std::size_t>(std::ceil(p / 100.0 * sorted.size()));
  return sorted[std::clamp<std::size_t>(rank, 1, sorted.size()) - 1];
}

int run(const std::vector<std::string>& argv) {
  const Args args(argv, {}, {"help", "json"});
  if (args.flag("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  if (args.positional().size() != 1) throw UsageError("expected one run folder");
  const std::string path = args.positional()[0] + "/events.jsonl";
  std::istringstream in(readTextFile(path));
  // Quantities by name, in ms; settle_s values seen.
  const std::vector<std::string> names = {"settle_error_ms", "settle_achieved_ms", "where_ms",
                                          "motion_to_disk_ms"};
  std::map<std::string, std::vector<double>> values_ms;
  std::map<double, int> settle_s_seen;
  DwellSummary dwell;
  int line_number = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_number;
    if (line.empty()) continue;
    json ev;
    try {
      ev = json::parse(line);
    } catch (const json::exception&) {
      std::fprintf(stderr, "%s:%d: not JSON, skipped\n", path.c_str(), line_number);
      continue;
    }
    try {
      dwell.add(ev);
    } catch (const json::exception& e) {
      std::fprintf(stderr, "%s:%d: %s, skipped\n", path.c_str(), line_number, e.what());
      continue;
    }
    if (ev.value("event", "") != "timing") continue;
    ++settle_s_seen[ev.value("settle_s", 0.0)];
    for (const auto& n : names)
      if (ev.contains(n) && ev[n].is_number()) values_ms[n].push_back(ev[n].get<double>());
  }
  const std::size_t count = values_ms["settle_error_ms"].size();
  if (count == 0) {
    std::fprintf(stderr, "%s: no timing events (a run of a robocald without dwell timing?)\n",
                 path.c_str());
    return 1;
  }
  json out = {{"points", count}};
  json settles = json::array();
  for (const auto& [s, n] : settle_s_seen) settles.push_back({{"settle_s", s}, {"points", n}});
  out["settle_s"] = settles;
  out["dwell"] = dwell.toJson();
  for (const auto& n : names) {
    std::vector<double> v = values_ms[n];
    std::sort(v.begin(), v.end());
    if (v.empty()) continue;
    out[n] = {{"p50", percentile(v, 50)},
              {"p99", percentile(v, 99)},
              {"max", v.back()},
              {"min", v.front()}};
  }
  if (args.flag("json")) {
    std::printf("%s\n", out.dump().c_str());
    return 0;
  }
  std::printf("%zu data points;", count);
  for (const auto& [s, n] : settle_s_seen) std::printf(" settle_s %.3f: %d", s, n);
  std::printf("\n%-20s %10s %10s %10s %10s\n", "ms", "min", "p50", "p99", "max");
  for (const auto& n : names) {
    if (!out.contains(n)) continue;
    std::printf("%-20s %10.3f %10.3f %10.3f %10.3f\n", n.c_str(), out[n]["min"].get<double>(),
                out[n]["p50"].get<double>(), out[n]["p99"].get<double>(),
                out[n]["max"].get<double>());
  }
  dwell.print();
  return 0;
}

const RegisterCommand r({"run-timing", "a daemon run's dwell timing (settle, motion to disk)",
                         run});

}  // namespace
}  // namespace robocal::cli
