#include <robocal/formats/iso_report.hpp>

#include "report_parts.hpp"

namespace robocal {
namespace {

using ojson = nlohmann::ordered_json;
using report_detail::fmt;

// What a ball-bar gives and what it cannot, said in every report.
const std::vector<std::string>& limits() {
  static const std::vector<std::string> kLimits = {
      "The bar measures one distance, chuck centre to ball centre: every figure is the pose's "
      "position error along the bar, not its full position (ISO 9283's AP, RP need three).",
      "Pose accuracy AP and repeatability RP in 3-D need the ball's position: three bars' "
      "distances from three chucks at the same pose (trilateration), i.e. the test run once per "
      "chuck with the same poses; not built.",
      "Orientation accuracy and repeatability are not measured: the bar does not see the tool's "
      "rotation about the ball.",
      "Distance accuracy between pose pairs is the change of the bar's length between them, one "
      "component of ISO 9283's AD, with the bar's nonlinearity in it (docs/realism.md).",
      "Path accuracy, cornering and overshoot need a tracker or a bar read during motion; "
      "the readings here are taken settled."};
  return kLimits;
}

ojson figureJson(const IsoFigure& f) {
  return {{"value", f.value_mm}, {"low95", f.low_mm}, {"high95", f.high_mm}};
}

// Accuracies signed, repeatabilities (3 s, never negative) not.
std::string figureText(const IsoFigure& f, bool sign = true) {
  return fmt(sign ? "%+.4f [%+.4f, %+.4f]" : "%7.4f [%.4f, %.4f]  ", f.value_mm, f.low_mm,
             f.high_mm);
}

}  // namespace

ojson isoJson(const IsoResult& r, const IsoConditions& c) {
  ojson j = {{"class", "ISO9283"},
             {"conditions",
              {{"model", c.model},
               {"samples", c.samples},
               {"cycles_planned", c.cycles_planned},
               {"spread_deg", c.spread_deg},
               {"date_utc", c.date_utc}}},
             {"connection", r.connection},
             {"extension_mm", r.extension_mm},
             {"warmup_cycles", r.warmup_cycles},
             {"readings", r.readings}};
  ojson poses = ojson::array();
  for (const IsoPose& p : r.poses)
    poses.push_back({{"name", p.name},
                     {"lat_deg", p.lat_deg},
                     {"lon_deg", p.lon_deg},
                     {"cycles", p.cycles},
                     {"commanded_mm", p.commanded_mm},
                     {"mean_attained_mm", p.mean_attained_mm},
                     {"distance_accuracy_mm", figureJson(p.accuracy)},
                     {"distance_repeatability_mm", figureJson(p.repeatability)}});
  j["poses"] = poses;
  ojson pairs = ojson::array();
  for (const IsoPair& p : r.pairs)
    pairs.push_back({{"from", p.from},
                     {"to", p.to},
                     {"cycles", p.cycles},
                     {"commanded_change_mm", p.commanded_change_mm},
                     {"distance_accuracy_mm", figureJson(p.accuracy)},
                     {"distance_repeatability_mm", figureJson(p.repeatability)}});
  j["pairs"] = pairs;
  if (r.drift.measured) {
    ojson d = figureJson(r.drift.change);
    d["span_min"] = r.drift.span_min;
    j["drift_mm"] = d;
  } else {
    j["drift_mm"] = nullptr;
  }
  j["limits"] = limits();
  return j;
}

std::string isoText(const IsoResult& r, const IsoConditions& c) {
  std::string out =
      "ISO 9283-style test with the ball-bar (figures along the bar, mm; "
      "[95 % interval])\n";
  out += "  model commanded: " + c.model + "\n  samples: " + c.samples + "\n";
  if (!c.date_utc.empty()) out += "  date (UTC): " + c.date_utc + "\n";
  out += "  connection " + r.connection + fmt(", extension %g mm; ", r.extension_mm) +
         std::to_string(r.warmup_cycles) + " warm-up cycle(s) left out; " +
         std::to_string(r.readings) + " readings" +
         (c.cycles_planned > 0 ? "; " + std::to_string(c.cycles_planned) + " cycles planned" : "") +
         (c.spread_deg > 0 ? fmt(", P2-P5 %g deg from P1", c.spread_deg) : "") + "\n\n";
  out += "pose  lat/lon (deg)    cycles  distance accuracy AD       distance repeatability RD\n";
  for (const IsoPose& p : r.poses)
    out += p.name + std::string(p.name.size() < 6 ? 6 - p.name.size() : 1, ' ') +
           fmt("%5.1f/%6.1f  ", p.lat_deg, p.lon_deg) + fmt("%6.0f  ", p.cycles) +
           figureText(p.accuracy) + "  " + figureText(p.repeatability, false) + "\n";
  if (!r.pairs.empty()) {
    out += "\npair    cycles  commanded change  AD of the change           RD of the change\n";
    for (const IsoPair& p : r.pairs)
      out += p.from + "-" + p.to + fmt("  %6.0f  ", p.cycles) +
             fmt("%+16.4f  ", p.commanded_change_mm) + figureText(p.accuracy) + "  " +
             figureText(p.repeatability, false) + "\n";
  }
  out += "\ndrift of P1: ";
  out += r.drift.measured
             ? figureText(r.drift.change) + fmt(" mm over %.1f min", r.drift.span_min) + "\n"
             : std::string("not measured (the samples carry no times)\n");
  out += "\nWhat a ball-bar cannot give:\n";
  for (const std::string& l : limits()) out += "  - " + l + "\n";
  return out;
}

}  // namespace robocal
