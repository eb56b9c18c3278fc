// The report of an ISO 9283-style test with the ball-bar (solver/iso9283.hpp): the figures with
// their 95 % intervals, the test's conditions, and what a ball-bar gives and what it cannot
// (docs/iso9283.md). JSON for tools (robocald writes iso9283.json in the run folder, `robocal iso
// --json` prints it) and text for people (iso9283.txt, `robocal iso`).
#pragma once

#include <robocal/solver/iso9283.hpp>

#include <nlohmann/json.hpp>
#include <string>

namespace robocal {

// How the test was run, as the standard asks a report to say.
struct IsoConditions {
  std::string model;       // the model the robot was commanded with (its name)
  std::string samples;     // the samples file, or the run
  int cycles_planned = 0;  // 0 when not known (samples without a plan)
  double spread_deg = 0;
  std::string date_utc;
};

// {"class": "ISO9283", "conditions": {...}, "connection", "extension_mm", "warmup_cycles",
//  "readings", "poses": [{"name", "lat_deg", "lon_deg", "cycles", "commanded_mm",
//  "mean_attained_mm", "distance_accuracy_mm": {"value", "low95", "high95"},
//  "distance_repeatability_mm": {...}}], "pairs": [{"from", "to", "cycles",
//  "commanded_change_mm", "distance_accuracy_mm", "distance_repeatability_mm"}],
//  "drift_mm": {"span_min", "value", "low95", "high95"} or null, "limits": [sentences]}.
nlohmann::ordered_json isoJson(const IsoResult& result, const IsoConditions& conditions);

// The same as a page of text: conditions, a table per kind of figure, the limits.
std::string isoText(const IsoResult& result, const IsoConditions& conditions);

}  // namespace robocal
