#include <robocal/planner/cell_json.hpp>
#include <robocal/planner/plan_json.hpp>

#include <robocal/jsonread/strict_json.hpp>

#include <cmath>
#include <nlohmann/json.hpp>

namespace robocal {
namespace {

using nlohmann::json;
using nlohmann::ordered_json;

constexpr int kMaxVisit = 10000;  // a reference pose every minute of a week-long shell

// Rounds to 1e-9 so that files stay readable; joints keep far more precision than the robot.
// Values too large to scale (which need no rounding) stay as they are, not infinity (null).
double tidy(double v) {
  const double rounded = std::round(v * 1e9) / 1e9 + 0.0;
  return std::isfinite(rounded) ? rounded : v;
}

ordered_json stepToJson(const PlanStep& s) {
  ordered_json j;
  j["kind"] = s.kind == StepKind::kPoint ? "point" : "via";
  ordered_json q = ordered_json::array();
  for (int k = 0; k < kJointCount; ++k) q.push_back(tidy(s.joints_deg[k]));
  j["joints_deg"] = q;
  j["lat_deg"] = tidy(s.lat_deg);
  j["lon_deg"] = tidy(s.lon_deg);
  if (s.visit > 0) j["visit"] = s.visit;
  if (s.stop) j["stop"] = true;
  return j;
}

// The plan's vocabulary on the strict reader: members that must be there, steps, counts.
class Reader {
 public:
  explicit Reader(const std::string& source) : r_(source) {}
  [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
    r_.fail(key, problem);
  }
  const json& member(const json& obj, const std::string& where, const char* key) const {
    return r_.member(obj, where, key);
  }
  double number(const json& obj, const std::string& where, const char* key) const {
    return r_.number(member(obj, where, key), jsonread::keyPath(where, key));
  }
  const json& array(const json& obj, const std::string& where, const char* key) const {
    return r_.array(member(obj, where, key), jsonread::keyPath(where, key));
  }
  std::string string(const json& obj, const std::string& where, const char* key) const {
    return r_.string(member(obj, where, key), jsonread::keyPath(where, key));
  }
  // A step; the connect pose has no "kind" (it is a point). No copy of `j` is made: copying a
  // deeply nested value recursed once per level and overflowed the stack.
  PlanStep step(const json& j, const std::string& where, bool has_kind = true) const {
    PlanStep s;
    const std::string kind = has_kind ? string(j, where, "kind") : "point";
    if (kind == "point") {
      s.kind = StepKind::kPoint;
    } else if (kind == "via") {
      s.kind = StepKind::kVia;
    } else {
      fail(where + ".kind", "expected \"point\" or \"via\", got \"" + kind + "\"");
    }
    const json& q = array(j, where, "joints_deg");
    if (q.size() != kJointCount) fail(where + ".joints_deg", "expected 6 joint readings in deg");
    for (int k = 0; k < kJointCount; ++k)
      s.joints_deg[k] = r_.number(q[k], jsonread::indexPath(where + ".joints_deg", k));
    s.lat_deg = number(j, where, "lat_deg");
    s.lon_deg = number(j, where, "lon_deg");
    s.visit = count(j, where, "visit", 0);
    if (const auto it = j.find("stop"); it != j.end()) {
      if (!it->is_boolean()) fail(where + ".stop", "expected true or false");
      s.stop = it->get<bool>();
    }
    if (s.visit > kMaxVisit)
      fail(where + ".visit", "expected 0 (first) to " + std::to_string(kMaxVisit) + " (revisits)");
    return s;
  }
  // An optional count of a summary (points, rank): a whole number from 0 to 1e9, else fallback
  // when absent.
  int count(const json& obj, const std::string& where, const char* key, int fallback) const {
    if (!obj.contains(key)) return fallback;
    const double v = number(obj, where, key);
    if (v != std::floor(v) || v < 0 || v > 1e9)
      fail(jsonread::keyPath(where, key), "expected a whole number from 0");
    return static_cast<int>(v);
  }

 private:
  jsonread::Reader<FormatError> r_;
};

}  // namespace

ordered_json planToJson(const Plan& plan) {
  ordered_json j;
  j["format"] = kPlanFormat;
  j["version"] = kPlanFormatVersion;
  j["model"] = plan.model_name;
  j["purpose"] = planPurposeName(plan.purpose);
  if (plan.iso)
    j["iso"] = {{"cycles", plan.iso->cycles},
                {"warmup_cycles", plan.iso->warmup_cycles},
                {"spread_deg", plan.iso->spread_deg}};
  const PlanSummary& s = plan.summary;
  ordered_json summary;
  summary["shells"] = s.shells;
  summary["points"] = s.points;
  summary["vias"] = s.vias;
  summary["dropped"] = s.dropped;
  summary["duration_s"] = tidy(s.duration_s);
  summary["swap_time_s"] = tidy(s.swap_time_s);
  summary["cell_time_s"] = tidy(s.cell_time_s);
  summary["max_deviation_mm"] = tidy(s.max_deviation_mm);
  if (s.predicted_deflection_mm >= 0) {
    summary["predicted_deflection_mm"] = tidy(s.predicted_deflection_mm);
    summary["predicted_change_from_connect_mm"] = tidy(s.predicted_change_mm);
  }
  if (s.rank > 0) {
    summary["rank"] = s.rank;
    summary["expected_rank"] = s.expected_rank;
    summary["condition_number"] = tidy(s.condition_number);
  }
  if (s.predicted_work_volume_error_mm >= 0) {
    summary["predicted_work_volume_error_mm"] = tidy(s.predicted_work_volume_error_mm);
    if (s.predicted_whole_range_error_mm >= 0)
      summary["predicted_whole_range_error_mm"] = tidy(s.predicted_whole_range_error_mm);
    summary["noise_sigma_mm"] = tidy(s.noise_sigma_mm);
  }
  j["summary"] = summary;
  j["settings"] = cellToJson(plan.cell);
  ordered_json shells = ordered_json::array();
  for (const ShellPlan& sh : plan.shells) {
    ordered_json o;
    o["shell"] = sh.shell;
    o["connection"] = connectionName(sh.connection);
    o["ball"] = sh.connection.ball_index + 1;
    o["chuck"] = sh.connection.chuck_index + 1;
    o["extension_mm"] = tidy(sh.extension_mm);
    o["radius_mm"] = tidy(sh.radius_mm);
    o["arm_configuration"] = armConfigName(sh.config);
    ordered_json ss;
    ss["points"] = sh.summary.points;
    ss["vias"] = sh.summary.vias;
    ss["duration_s"] = tidy(sh.summary.duration_s);
    ss["max_deviation_mm"] = tidy(sh.summary.max_deviation_mm);
    if (sh.summary.predicted_deflection_mm >= 0) {
      ss["predicted_deflection_mm"] = tidy(sh.summary.predicted_deflection_mm);
      ss["predicted_change_from_connect_mm"] = tidy(sh.summary.predicted_change_mm);
    }
    o["summary"] = ss;
    o["connect"] = stepToJson(sh.connect);
    o["connect"].erase("kind");
    ordered_json steps = ordered_json::array();
    for (const PlanStep& st : sh.steps) steps.push_back(stepToJson(st));
    o["steps"] = steps;
    ordered_json dropped = ordered_json::array();
    for (const DroppedPoint& d : sh.dropped)
      dropped.push_back(
          {{"lat_deg", tidy(d.lat_deg)}, {"lon_deg", tidy(d.lon_deg)}, {"reason", d.reason}});
    o["dropped"] = dropped;
    shells.push_back(o);
  }
  j["shells"] = shells;
  return j;
}

std::string formatPlan(const Plan& plan) {
  // Pretty JSON, but one line per step so that a plan of thousands of steps stays readable.
  ordered_json j = planToJson(plan);
  std::vector<std::string> step_blocks;
  for (auto& shell : j["shells"]) {
    std::string block = "[";
    const auto& steps = shell["steps"];
    for (size_t i = 0; i < steps.size(); ++i)
      block += std::string(i == 0 ? "\n" : ",\n") + "    " + steps[i].dump();
    block += steps.empty() ? "]" : "\n   ]";
    shell["steps"] = "@@steps" + std::to_string(step_blocks.size()) + "@@";
    step_blocks.push_back(std::move(block));
  }
  std::string text = j.dump(1);
  for (size_t i = 0; i < step_blocks.size(); ++i) {
    const std::string key = "\"@@steps" + std::to_string(i) + "@@\"";
    const size_t at = text.find(key);
    if (at != std::string::npos) text.replace(at, key.size(), step_blocks[i]);
  }
  return text + "\n";
}

Plan planFromJson(const json& root, const std::string& source) {
  const Reader r(source);
  if (!root.is_object()) r.fail("top level", "expected an object");
  if (r.string(root, "", "format") != kPlanFormat)
    r.fail("format", std::string("expected \"") + kPlanFormat + "\"");
  const json& version = r.member(root, "", "version");
  if (!version.is_number_integer() || version.get<int>() != kPlanFormatVersion)
    r.fail("version", "expected " + std::to_string(kPlanFormatVersion) + ", got " +
                          (version.is_structured() ? version.type_name() : version.dump()));
  Plan plan;
  if (root.contains("model") && root["model"].is_string()) plan.model_name = root["model"];
  // Files older than the health check have no purpose: they are calibration plans.
  if (root.contains("purpose")) {
    const std::string purpose = r.string(root, "", "purpose");
    const auto parsed = parsePlanPurpose(purpose);
    if (!parsed)
      r.fail("purpose",
             "expected \"calibration\", \"check\" or \"iso9283\", got \"" + purpose + "\"");
    plan.purpose = *parsed;
  }
  if (plan.purpose == PlanPurpose::kIsoTest) {
    const json& iso = r.member(root, "", "iso");
    IsoTestSettings t;
    auto whole = [&](const char* key, int lo, int hi) {
      const double v = r.number(iso, "iso", key);
      if (v != std::floor(v) || v < lo || v > hi)
        r.fail(std::string("iso.") + key,
               "expected a whole number from " + std::to_string(lo) + " to " + std::to_string(hi));
      return static_cast<int>(v);
    };
    t.cycles = whole("cycles", 2, 1000);
    t.warmup_cycles = whole("warmup_cycles", 0, 1000);
    t.spread_deg = r.number(iso, "iso", "spread_deg");
    plan.iso = t;
  }
  plan.cell = cellFromJson(r.member(root, "", "settings"), source + ": settings");
  const json& shells = r.array(root, "", "shells");
  for (size_t i = 0; i < shells.size(); ++i) {
    const std::string where = "shells[" + std::to_string(i) + "]";
    const json& o = shells[i];
    ShellPlan sh;
    const double number = r.number(o, where, "shell");
    if (number != std::floor(number) || number < 1 || number > 1e6)
      r.fail(where + ".shell", "expected 1, 2, ... (at most 1000000)");
    sh.shell = static_cast<int>(number);
    try {
      const auto c = parseConnections(r.string(o, where, "connection"));
      if (c.size() != 1) r.fail(where + ".connection", "expected one connection like B1C2");
      sh.connection = c[0];
    } catch (const std::invalid_argument& e) {
      r.fail(where + ".connection", e.what());
    }
    sh.extension_mm = r.number(o, where, "extension_mm");
    sh.radius_mm = r.number(o, where, "radius_mm");
    const std::string config = r.string(o, where, "arm_configuration");
    const auto parsed = parseArmConfig(config);
    if (!parsed)
      r.fail(where + ".arm_configuration",
             "unknown configuration \"" + config + "\" (one of " + armConfigNames() + ")");
    sh.config = *parsed;
    sh.connect = r.step(r.member(o, where, "connect"), where + ".connect", false);
    const json& steps = r.array(o, where, "steps");
    for (size_t k = 0; k < steps.size(); ++k)
      sh.steps.push_back(r.step(steps[k], where + ".steps[" + std::to_string(k) + "]"));
    if (o.contains("dropped") && o["dropped"].is_array())
      for (size_t k = 0; k < o["dropped"].size(); ++k) {
        const std::string dw = where + ".dropped[" + std::to_string(k) + "]";
        const json& d = o["dropped"][k];
        sh.dropped.push_back({r.number(d, dw, "lat_deg"), r.number(d, dw, "lon_deg"),
                              d.contains("reason") && d["reason"].is_string()
                                  ? d["reason"].get<std::string>()
                                  : std::string()});
      }
    if (o.contains("summary") && o["summary"].is_object()) {
      const json& ss = o["summary"];
      sh.summary.points = r.count(ss, where + ".summary", "points", 0);
      sh.summary.vias = r.count(ss, where + ".summary", "vias", 0);
      sh.summary.duration_s = ss.value("duration_s", 0.0);
      sh.summary.max_deviation_mm = ss.value("max_deviation_mm", 0.0);
      sh.summary.predicted_deflection_mm = ss.value("predicted_deflection_mm", -1.0);
      sh.summary.predicted_change_mm = ss.value("predicted_change_from_connect_mm", -1.0);
    }
    plan.shells.push_back(std::move(sh));
  }
  summarizePlan(plan);
  if (root.contains("summary") && root["summary"].is_object()) {
    const json& s = root["summary"];
    plan.summary.rank = r.count(s, "summary", "rank", 0);
    plan.summary.expected_rank = r.count(s, "summary", "expected_rank", 36);
    plan.summary.condition_number = s.value("condition_number", 0.0);
    plan.summary.predicted_work_volume_error_mm = s.value("predicted_work_volume_error_mm", -1.0);
    plan.summary.predicted_whole_range_error_mm = s.value("predicted_whole_range_error_mm", -1.0);
    plan.summary.noise_sigma_mm = s.value("noise_sigma_mm", 0.0);
  }
  return plan;
}

Plan parsePlan(const std::string& text, const std::string& source) {
  const json j = jsonread::parseText<FormatError>(text, source, "a plan (docs/plan-format.md)");
  try {
    return planFromJson(j, source);
  } catch (const json::exception& e) {
    throw FormatError(source + ": " + e.what());
  }
}

Plan loadPlanFile(const std::string& path) {
  return parsePlan(readTextFile(path), path);
}

void savePlanFile(const std::string& path, const Plan& plan) {
  writeTextFileAtomic(path, formatPlan(plan));
}

}  // namespace robocal
