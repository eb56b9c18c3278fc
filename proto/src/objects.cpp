#include <robocal/proto/objects.hpp>

#include "wire_names.hpp"

#include <array>
#include <limits>
#include <utility>

namespace robocal::proto {
namespace {

using json = nlohmann::json;

constexpr std::array<std::pair<PromptAction, const char*>, 2> kPromptActions = {
    {{PromptAction::kConnect, "connect"}, {PromptAction::kDetach, "detach"}}};

constexpr std::array<BarKind, 4> kBarKinds = {BarKind::kReading, BarKind::kOverRange,
                                              BarKind::kNoProbe, BarKind::kDeviceError};

// Reads the fields of one object (or of a nested part of it: `path` is "devices." for STATUS's
// devices) and says, on any problem, which class and which field.
class Reader {
 public:
  Reader(const json& object, std::string cls, std::string path = {})
      : obj_(object), cls_(std::move(cls)), path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
    throw ObjectError(cls_ + ": field '" + path_ + key + "' " + problem);
  }

  // The field, or nullptr when it is absent or null (allowed only when not required).
  const json* find(const std::string& key, bool required) const {
    const auto it = obj_.find(key);
    if (it == obj_.end() || it->is_null()) {
      if (required) fail(key, it == obj_.end() ? "is missing" : "is null");
      return nullptr;
    }
    return &*it;
  }

  const json& typed(const std::string& key, bool ok, const json& v, const char* what) const {
    if (!ok) fail(key, std::string("must be ") + what + ", got " + v.type_name());
    return v;
  }

  std::optional<std::string> optString(const std::string& key, bool required = false) const {
    const json* v = find(key, required);
    if (!v) return std::nullopt;
    return typed(key, v->is_string(), *v, "a string").get<std::string>();
  }
  std::string string(const std::string& key) const { return *optString(key, true); }

  std::optional<std::int64_t> optInteger(const std::string& key, bool required = false) const {
    const json* v = find(key, required);
    if (!v) return std::nullopt;
    typed(key, v->is_number_integer(), *v, "a whole number");
    if (v->is_number_unsigned() &&
        v->get<std::uint64_t>() >
            static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))
      fail(key, "is out of range");
    return v->get<std::int64_t>();
  }
  std::optional<int> optInt(const std::string& key, bool required = false) const {
    const auto v = optInteger(key, required);
    if (!v) return std::nullopt;
    if (*v < std::numeric_limits<int>::min() || *v > std::numeric_limits<int>::max())
      fail(key, "is out of range");
    return static_cast<int>(*v);
  }
  int integer(const std::string& key) const { return *optInt(key, true); }

  std::optional<double> optNumber(const std::string& key, bool required = false) const {
    const json* v = find(key, required);
    if (!v) return std::nullopt;
    return typed(key, v->is_number(), *v, "a number").get<double>();
  }
  double number(const std::string& key) const { return *optNumber(key, true); }

  bool boolean(const std::string& key) const {
    const json* v = find(key, true);
    return typed(key, v->is_boolean(), *v, "true or false").get<bool>();
  }

  const json& object(const std::string& key) const {
    const json* v = find(key, true);
    return typed(key, v->is_object(), *v, "an object");
  }
  const json& array(const std::string& key) const {
    const json* v = find(key, true);
    return typed(key, v->is_array(), *v, "an array");
  }

  // An enum field: `parse` maps the wire name; `names` lists them for the message.
  template <class E, class Parse>
  E enumField(const std::string& key, Parse parse, const char* names) const {
    const std::string name = string(key);
    const std::optional<E> e = parse(name);
    if (!e) fail(key, "is \"" + name + "\", not one of " + names);
    return *e;
  }

  // A nested server object of another class (STATUS's bar, prompt, plan); nullopt when null.
  template <class T>
  std::optional<T> nested(const std::string& key, bool required_key) const {
    if (required_key && !obj_.contains(key)) fail(key, "is missing");
    const json* v = find(key, false);
    if (!v) return std::nullopt;
    try {
      return parseObject<T>(*v);
    } catch (const ObjectError& e) {
      fail(key, std::string("is not a ") + T::kClass + ": " + e.what());
    }
  }

  Reader part(const json& sub, const std::string& key) const {
    return Reader(sub, cls_, path_ + key + ".");
  }
  Reader element(const json& sub, const std::string& key, std::size_t i) const {
    return Reader(sub, cls_, path_ + key + "[" + std::to_string(i) + "].");
  }

 private:
  const json& obj_;
  std::string cls_;
  std::string path_;
};

// Checks that `object` is a server object of class `cls`.
Reader open(const json& object, const char* cls) {
  if (!object.is_object())
    throw ObjectError(std::string(cls) + ": expected a JSON object, got " + object.type_name());
  const std::string got = objectClass(object);
  if (got != cls)
    throw ObjectError(std::string(cls) + ": field 'class' is " +
                      (object.contains("class") ? "\"" + got + "\"" : std::string("missing")) +
                      ", not \"" + cls + "\"");
  return Reader(object, cls);
}

json nullOr(const auto& optional) {
  return optional ? toJson(*optional) : json();
}

}  // namespace

const char* promptActionName(PromptAction action) {
  return wireName(kPromptActions, action, "?");
}

std::optional<PromptAction> parsePromptAction(std::string_view name) {
  return wireValue(kPromptActions, name);
}

std::optional<BarKind> parseBarKind(std::string_view name) {
  for (const BarKind k : kBarKinds)
    if (name == barKindName(k)) return k;
  return std::nullopt;
}

std::string objectClass(const json& object) {
  if (!object.is_object()) return {};
  const auto it = object.find("class");
  return it != object.end() && it->is_string() ? it->get<std::string>() : std::string();
}

// ------------------------------------------------------------------ VERSION, ERROR, ACK, WATCH
json toJson(const Version& o) {
  return {{"class", Version::kClass},
          {"release", o.release},
          {"proto_major", o.proto_major},
          {"proto_minor", o.proto_minor}};
}
template <>
Version parseObject<Version>(const json& j) {
  const Reader r = open(j, Version::kClass);
  return {r.string("release"), r.integer("proto_major"), r.integer("proto_minor")};
}

json toJson(const Error& o) {
  json j = {{"class", Error::kClass}, {"message", o.message}};
  if (o.cmd) j["cmd"] = *o.cmd;
  if (o.violations) j["violations"] = *o.violations;
  return j;
}
template <>
Error parseObject<Error>(const json& j) {
  const Reader r = open(j, Error::kClass);
  Error e{r.string("message"), r.optString("cmd"), std::nullopt};
  if (r.find("violations", false)) {
    std::vector<std::string> list;
    for (const json& v : r.array("violations")) {
      if (!v.is_string())
        r.fail("violations", std::string("must hold strings, got ") + v.type_name());
      list.push_back(v.get<std::string>());
    }
    e.violations = std::move(list);
  }
  return e;
}

json toJson(const Ack& o) {
  json j = {{"class", Ack::kClass}, {"cmd", cmdName(o.cmd)}};
  if (o.message) j["message"] = *o.message;
  return j;
}
template <>
Ack parseObject<Ack>(const json& j) {
  const Reader r = open(j, Ack::kClass);
  return {r.enumField<Cmd>("cmd", parseCmd,
                           "status, watch, plan, start, confirm, nudge, pause, resume, abort, "
                           "result, runs"),
          r.optString("message")};
}

json toJson(const Watch& o) {
  return {{"class", Watch::kClass}, {"enable", o.enable}};
}
template <>
Watch parseObject<Watch>(const json& j) {
  return {open(j, Watch::kClass).boolean("enable")};
}

// ------------------------------------------------------------------ the live stream
json toJson(const Bar& o) {
  json j = {
      {"class", Bar::kClass}, {"seq", o.seq}, {"kind", barKindName(o.kind)}, {"t_us", o.t_us}};
  if (o.deflection_mm) j["deflection_mm"] = *o.deflection_mm;
  if (o.length_mm) j["length_mm"] = *o.length_mm;
  return j;
}
template <>
Bar parseObject<Bar>(const json& j) {
  const Reader r = open(j, Bar::kClass);
  Bar b;
  const std::int64_t seq = *r.optInteger("seq", true);
  if (seq < 0) r.fail("seq", "must not be negative");
  b.seq = static_cast<std::uint64_t>(seq);
  b.kind =
      r.enumField<BarKind>("kind", parseBarKind, "reading, over_range, no_probe, device_error");
  b.deflection_mm = r.optNumber("deflection_mm");
  b.length_mm = r.optNumber("length_mm");
  b.t_us = *r.optInteger("t_us", true);
  return b;
}

json toJson(const Progress& o) {
  return {{"class", Progress::kClass},
          {"shell", o.shell},
          {"shells", o.shells},
          {"connection", o.connection},
          {"points_done", o.points_done},
          {"points_total", o.points_total},
          {"eta_s", o.eta_s}};
}
template <>
Progress parseObject<Progress>(const json& j) {
  const Reader r = open(j, Progress::kClass);
  return {r.integer("shell"),       r.integer("shells"),       r.string("connection"),
          r.integer("points_done"), r.integer("points_total"), r.number("eta_s")};
}

namespace {
constexpr const char* kRunStateNames =
    "idle, checking, moving, awaiting_confirm, measuring, paused, interrupted, solving, done, "
    "aborted, error";
}  // namespace

json toJson(const State& o) {
  return {{"class", State::kClass},
          {"from", runStateName(o.from)},
          {"to", runStateName(o.to)},
          {"reason", o.reason}};
}
template <>
State parseObject<State>(const json& j) {
  const Reader r = open(j, State::kClass);
  return {r.enumField<RunState>("from", parseRunState, kRunStateNames),
          r.enumField<RunState>("to", parseRunState, kRunStateNames),
          r.optString("reason").value_or("")};
}

json toJson(const Prompt& o) {
  json j = {{"class", Prompt::kClass},
            {"action", promptActionName(o.action)},
            {"shell", o.shell},
            {"message", o.message}};
  if (o.ball) j["ball"] = *o.ball;
  if (o.chuck) j["chuck"] = *o.chuck;
  if (o.extension_mm) j["extension_mm"] = *o.extension_mm;
  return j;
}
template <>
Prompt parseObject<Prompt>(const json& j) {
  const Reader r = open(j, Prompt::kClass);
  Prompt p;
  p.action = r.enumField<PromptAction>("action", parsePromptAction, "connect, detach");
  p.shell = r.integer("shell");
  // A connect prompt always says what to connect.
  const bool connect = p.action == PromptAction::kConnect;
  p.ball = r.optInt("ball", connect);
  p.chuck = r.optInt("chuck", connect);
  p.extension_mm = r.optNumber("extension_mm", connect);
  p.message = r.string("message");
  return p;
}

json toJson(const Sample& o) {
  return {{"class", Sample::kClass},  {"shell", o.shell},       {"lat_deg", o.lat_deg},
          {"lon_deg", o.lon_deg},     {"joints", o.joints},     {"length_mm", o.length_mm},
          {"spread_mm", o.spread_mm}, {"readings", o.readings}, {"dwell_s", o.dwell_s}};
}
template <>
Sample parseObject<Sample>(const json& j) {
  const Reader r = open(j, Sample::kClass);
  Sample s;
  s.shell = r.integer("shell");
  s.lat_deg = r.number("lat_deg");
  s.lon_deg = r.number("lon_deg");
  for (const json& q : r.array("joints")) {
    if (!q.is_number()) r.fail("joints", std::string("must hold numbers, got ") + q.type_name());
    s.joints.push_back(q.get<double>());
  }
  s.length_mm = r.number("length_mm");
  s.spread_mm = r.number("spread_mm");
  s.readings = r.integer("readings");
  s.dwell_s = r.number("dwell_s");
  return s;
}

json toJson(const Event& o) {
  json j = o.details.is_object() ? o.details : json::object();
  j["class"] = Event::kClass;
  j["event"] = o.event;
  return j;
}
template <>
Event parseObject<Event>(const json& j) {
  const Reader r = open(j, Event::kClass);
  Event e{r.string("event"), j};
  e.details.erase("class");
  e.details.erase("event");
  return e;
}

// ------------------------------------------------------------------ replies
json toJson(const Plan& o) {
  return {{"class", Plan::kClass},
          {"source", o.source},
          {"shells", o.shells},
          {"points", o.points},
          {"vias", o.vias},
          {"dropped", o.dropped},
          {"duration_s", o.duration_s},
          {"rank", o.rank},
          {"condition_number", o.condition_number},
          {"max_deviation_mm", o.max_deviation_mm},
          {"predicted_deflection_mm", o.predicted_deflection_mm},
          {"predicted_change_mm", o.predicted_change_mm},
          {"predicted_work_volume_error_mm", o.predicted_work_volume_error_mm},
          {"predicted_whole_range_error_mm", o.predicted_whole_range_error_mm}};
}
template <>
Plan parseObject<Plan>(const json& j) {
  const Reader r = open(j, Plan::kClass);
  Plan p;
  p.source = r.string("source");
  p.shells = r.integer("shells");
  p.points = r.integer("points");
  p.vias = r.integer("vias");
  p.dropped = r.integer("dropped");
  p.duration_s = r.number("duration_s");
  p.rank = r.integer("rank");
  p.condition_number = r.number("condition_number");
  p.max_deviation_mm = r.number("max_deviation_mm");
  p.predicted_deflection_mm = r.number("predicted_deflection_mm");
  p.predicted_change_mm = r.number("predicted_change_mm");
  p.predicted_work_volume_error_mm = r.number("predicted_work_volume_error_mm");
  p.predicted_whole_range_error_mm = r.number("predicted_whole_range_error_mm");
  return p;
}

namespace {
constexpr std::array<const char*, 6> kResultRunFields = {
    "run", "set", "extension_mm", "calibrated_file", "report_dir", "samples_file"};
}  // namespace

json toJson(const Result& o) {
  if (!o.available)
    return {{"class", Result::kClass}, {"available", false}, {"message", o.message}};
  json j = o.fit.is_object() ? o.fit : json::object();
  j.erase("available");
  j.erase("message");
  j["class"] = Result::kClass;
  j["run"] = o.run;
  j["set"] = o.set;
  j["extension_mm"] = o.extension_mm;
  j["calibrated_file"] = o.calibrated_file;
  j["report_dir"] = o.report_dir;
  j["samples_file"] = o.samples_file;
  return j;
}
template <>
Result parseObject<Result>(const json& j) {
  const Reader r = open(j, Result::kClass);
  Result res;
  if (r.find("available", false) && !r.boolean("available")) {
    res.available = false;
    res.message = r.optString("message").value_or("");
    return res;
  }
  res.run = r.string("run");
  res.set = r.integer("set");
  res.extension_mm = r.number("extension_mm");
  res.calibrated_file = r.string("calibrated_file");
  res.report_dir = r.string("report_dir");
  res.samples_file = r.string("samples_file");
  res.fit = j;
  res.fit.erase("class");
  res.fit.erase("available");
  for (const char* key : kResultRunFields) res.fit.erase(key);
  return res;
}

json toJson(const Runs& o) {
  json list = json::array();
  for (const RunEntry& e : o.runs)
    list.push_back({{"run", e.run}, {"status", e.status}, {"reason", e.reason}});
  return {{"class", Runs::kClass}, {"runs", list}};
}
template <>
Runs parseObject<Runs>(const json& j) {
  const Reader r = open(j, Runs::kClass);
  Runs out;
  const json& list = r.array("runs");
  for (std::size_t i = 0; i < list.size(); ++i) {
    if (!list[i].is_object())
      r.fail("runs[" + std::to_string(i) + "]",
             std::string("must be an object, got ") + list[i].type_name());
    const Reader e = r.element(list[i], "runs", i);
    out.runs.push_back({e.string("run"), e.string("status"), e.string("reason")});
  }
  return out;
}

json toJson(const Status& o) {
  json devices = {{"val", o.devices.val}, {"bar", o.devices.bar}};
  if (o.devices.val_error) devices["val_error"] = *o.devices.val_error;
  if (o.devices.bar_error) devices["bar_error"] = *o.devices.bar_error;
  return {{"class", Status::kClass},
          {"state", runStateName(o.state)},
          {"reason", o.reason},
          {"run", o.run},
          {"shell", o.shell},
          {"shells", o.shells},
          {"connection", o.connection},
          {"points_done", o.points_done},
          {"points_total", o.points_total},
          {"eta_s", o.eta_s},
          {"bar_attached", o.bar_attached},
          {"devices", devices},
          {"bar", nullOr(o.bar)},
          {"prompt", nullOr(o.prompt)},
          {"resumable", o.resumable},
          {"clients", o.clients},
          {"client_counts",
           {{"refused", o.client_counts.refused},
            {"stalled", o.client_counts.stalled},
            {"timed_out", o.client_counts.timed_out},
            {"dropped_lines", o.client_counts.dropped_lines}}},
          {"plan", nullOr(o.plan)}};
}
template <>
Status parseObject<Status>(const json& j) {
  const Reader r = open(j, Status::kClass);
  Status s;
  s.state = r.enumField<RunState>("state", parseRunState, kRunStateNames);
  s.reason = r.string("reason");
  s.run = r.string("run");
  s.shell = r.integer("shell");
  s.shells = r.integer("shells");
  s.connection = r.string("connection");
  s.points_done = r.integer("points_done");
  s.points_total = r.integer("points_total");
  s.eta_s = r.number("eta_s");
  s.bar_attached = r.boolean("bar_attached");
  const Reader d = r.part(r.object("devices"), "devices");
  s.devices.val = d.boolean("val");
  s.devices.bar = d.boolean("bar");
  s.devices.val_error = d.optString("val_error");
  s.devices.bar_error = d.optString("bar_error");
  s.bar = r.nested<Bar>("bar", true);
  s.prompt = r.nested<Prompt>("prompt", true);
  s.resumable = r.string("resumable");
  s.clients = r.integer("clients");
  const Reader cc = r.part(r.object("client_counts"), "client_counts");
  s.client_counts = {*cc.optInteger("refused", true), *cc.optInteger("stalled", true),
                     *cc.optInteger("timed_out", true), *cc.optInteger("dropped_lines", true)};
  s.plan = r.nested<Plan>("plan", true);
  return s;
}

namespace {
json sixOrNull(const std::optional<std::array<double, 6>>& v) {
  return v ? json(*v) : json(nullptr);
}
std::optional<std::array<double, 6>> readSix(const Reader& r, const json& j,
                                             const std::string& key) {
  const auto it = j.find(key);
  if (it == j.end() || it->is_null()) return std::nullopt;
  if (!it->is_array() || it->size() != 6) r.fail(key, "must be an array of 6 numbers");
  std::array<double, 6> out{};
  for (std::size_t k = 0; k < 6; ++k) {
    if (!(*it)[k].is_number()) r.fail(key, "must hold numbers");
    out[k] = (*it)[k].get<double>();
  }
  return out;
}
std::vector<std::string> readStrings(const Reader& r, const json& list, const std::string& key) {
  std::vector<std::string> out;
  for (const json& v : list) {
    if (!v.is_string()) r.fail(key, "must hold strings");
    out.push_back(v.get<std::string>());
  }
  return out;
}
}  // namespace

json toJson(const Models& o) {
  json list = json::array();
  for (const ModelEntry& m : o.models) {
    json checks = json::array();
    for (const HealthCheckEntry& c : m.checks)
      checks.push_back(
          {{"run", c.run}, {"date_utc", c.date_utc}, {"verdict", c.verdict}, {"rms_mm", c.rms_mm}});
    json e = {{"version", m.version},
              {"file", m.file},
              {"date_utc", m.date_utc},
              {"run", m.run},
              {"set", m.set},
              {"samples", m.samples},
              {"fit_rms_mm", m.fit_rms_mm},
              {"rank", m.rank},
              {"usable", m.usable},
              {"problems", m.problems},
              {"checks", checks},
              {"active", m.active}};
    e["work_volume_error_mm"] = m.work_volume_error_mm ? json(*m.work_volume_error_mm) : json();
    list.push_back(e);
  }
  return {{"class", Models::kClass},
          {"active", o.active ? json(*o.active) : json(nullptr)},
          {"models", list}};
}
template <>
Models parseObject<Models>(const json& j) {
  const Reader r = open(j, Models::kClass);
  Models out;
  out.active = r.optInt("active");
  const json& list = r.array("models");
  for (std::size_t i = 0; i < list.size(); ++i) {
    if (!list[i].is_object())
      r.fail("models[" + std::to_string(i) + "]", std::string("must be an object"));
    const Reader e = r.element(list[i], "models", i);
    ModelEntry m;
    m.version = e.integer("version");
    m.file = e.string("file");
    m.date_utc = e.string("date_utc");
    m.run = e.string("run");
    m.set = e.integer("set");
    m.samples = e.integer("samples");
    m.fit_rms_mm = e.number("fit_rms_mm");
    m.rank = e.integer("rank");
    m.usable = e.boolean("usable");
    m.problems = readStrings(e, e.array("problems"), "problems");
    m.work_volume_error_mm = e.optNumber("work_volume_error_mm");
    const json& checks = e.array("checks");
    for (std::size_t k = 0; k < checks.size(); ++k) {
      const Reader c = e.element(checks[k], "checks", k);
      m.checks.push_back(
          {c.string("run"), c.string("date_utc"), c.string("verdict"), c.number("rms_mm")});
    }
    m.active = e.boolean("active");
    out.models.push_back(std::move(m));
  }
  return out;
}

json toJson(const Compensated& o) {
  json rows = json::array();
  for (const CompensatedRow& t : o.targets)
    rows.push_back(
        {{"name", t.name},
         {"status", t.status},
         {"config", t.config},
         {"note", t.note},
         {"joints_deg", sixOrNull(t.joints_deg)},
         {"predicted_error_mm", t.predicted_error_mm ? json(*t.predicted_error_mm) : json(nullptr)},
         {"pre_point_joints_deg", sixOrNull(t.pre_point_joints_deg)}});
  return {{"class", Compensated::kClass}, {"model", o.model}, {"targets", rows}};
}
template <>
Compensated parseObject<Compensated>(const json& j) {
  const Reader r = open(j, Compensated::kClass);
  Compensated out;
  out.model = r.integer("model");
  const json& rows = r.array("targets");
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!rows[i].is_object())
      r.fail("targets[" + std::to_string(i) + "]", std::string("must be an object"));
    const Reader e = r.element(rows[i], "targets", i);
    CompensatedRow t;
    t.name = e.string("name");
    t.status = e.string("status");
    t.config = e.string("config");
    t.note = e.string("note");
    t.joints_deg = readSix(e, rows[i], "joints_deg");
    t.predicted_error_mm = e.optNumber("predicted_error_mm");
    t.pre_point_joints_deg = readSix(e, rows[i], "pre_point_joints_deg");
    out.targets.push_back(std::move(t));
  }
  return out;
}

json toJson(const Check& o) {
  if (!o.available) return {{"class", Check::kClass}, {"available", false}, {"message", o.message}};
  return {{"class", Check::kClass}, {"run", o.run},       {"model_version", o.model_version},
          {"date_utc", o.date_utc}, {"status", o.status}, {"text", o.text},
          {"verdict", o.verdict}};
}
template <>
Check parseObject<Check>(const json& j) {
  const Reader r = open(j, Check::kClass);
  Check out;
  if (r.find("available", false) && !r.boolean("available")) {
    out.available = false;
    out.message = r.optString("message").value_or("");
    return out;
  }
  out.run = r.string("run");
  out.model_version = r.integer("model_version");
  out.date_utc = r.string("date_utc");
  out.status = r.string("status");
  out.text = r.string("text");
  out.verdict = r.object("verdict");
  return out;
}

}  // namespace robocal::proto
