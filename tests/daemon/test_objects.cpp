// The server objects as structs (proto/objects.hpp): each class round-trips, a malformed object
// is refused naming its class and field, and docs/protocol.md's "Server objects" table names
// every class and every field the structs emit.
#include <catch2/catch.hpp>

#include <robocal/formats/error.hpp>
#include <robocal/proto/objects.hpp>

#include <map>
#include <regex>
#include <set>
#include <string>

using namespace robocal::proto;
using Catch::Matchers::Contains;
using json = nlohmann::json;

namespace {

// One object of each class with every optional field filled.
Bar fullBar() {
  return {5301, BarKind::kReading, 0.0412, 150.0412, 93112420};
}
Prompt fullPrompt() {
  return {PromptAction::kConnect,
          1,
          1,
          3,
          150.0,
          "Connect ball 1 to chuck 3 with the 150 mm extension, then confirm."};
}
Plan fullPlan() {
  return {
      "/etc/robocald/cell.json", 18, 1714, 40, 2, 5400.5, 36, 812.0, 0.42, 0.031, 0.9, 0.047, 0.55};
}
Status fullStatus() {
  Status s;
  s.state = RunState::kAwaitingConfirm;
  s.reason = "Connect ball 1 to chuck 3, then confirm.";
  s.run = "2026-12-01T16-16-26";
  s.shell = 1;
  s.shells = 18;
  s.connection = "B1C3";
  s.points_done = 12;
  s.points_total = 1714;
  s.eta_s = 3600.25;
  s.bar_attached = true;
  s.devices = {true, false, std::nullopt, "/dev/ttyUSB1: no such device"};
  s.bar = fullBar();
  s.prompt = fullPrompt();
  s.resumable = "2026-11-30T10-00-00";
  s.clients = 2;
  s.plan = fullPlan();
  return s;
}
Result fullResult() {
  Result r;
  r.run = "2026-12-01T16-16-26";
  r.set = 2;
  r.extension_mm = 150;
  r.calibrated_file = "/var/lib/robocald/runs/x/calibrated-set2.json";
  r.report_dir = "/var/lib/robocald/runs/x/report-set2";
  r.samples_file = "/var/lib/robocald/runs/x/samples.csv";
  r.fit = {{"n", 860},
           {"rank", 36},
           {"rms_mm", 0.0299},
           {"problems", json::array()},
           {"validation_rms_mm", 0.041},
           {"prediction", {{"n", 850}, {"rms_mm", 0.041}, {"max_abs_mm", 0.12}}}};
  return r;
}
Models fullModels() {
  ModelEntry m;
  m.version = 3;
  m.file = "/var/lib/robocald/models/model-0003.json";
  m.date_utc = "2026-12-02T08:00:00Z";
  m.run = "2026-12-02T07-00-00";
  m.set = 2;
  m.samples = 1714;
  m.fit_rms_mm = 0.082;
  m.rank = 36;
  m.usable = true;
  m.problems = {"none really"};
  m.work_volume_error_mm = 0.047;
  m.checks = {{"2026-12-03T07-00-00", "2026-12-03T07:10:00Z", "pass", 0.09}};
  m.active = true;
  return {3, {m}};
}
Compensated fullCompensated() {
  return {3,
          {{"p1", "ok", "right-up-noflip", "", std::array<double, 6>{1, 2, 3, 4, 5, 6}, 0.05,
            std::array<double, 6>{0.98, 1.98, 2.98, 3.98, 4.98, 5.98}},
           {"p2", "unreachable", "right-up-noflip", "out of reach", std::nullopt, std::nullopt,
            std::nullopt}}};
}
Check fullCheck() {
  return {true,
          "",
          "2026-12-03T07-00-00",
          3,
          "2026-12-03T07:10:00Z",
          "fail",
          "health check: FAIL\n",
          {{"status", "fail"}, {"rms_mm", 0.3}}};
}
Event connectionCheck() {
  return {"connection_check",
          {{"shell", 3},
           {"connection", "B1C3"},
           {"steps", {{{"commanded_mm", 0.5}, {"reading_change_mm", 0.49}}}},
           {"ok", true}}};
}

// Every server object with every field it can carry, by class.
std::map<std::string, json> fullObjects() {
  return {{"VERSION", toJson(Version{"0.1.0"})},
          {"ERROR", toJson(Error{"2 safety violations", "start", {{"shell 3: joint 5", "x"}}})},
          {"ACK", toJson(Ack{Cmd::kStart, "run starting with /etc/robocald/cell.json"})},
          {"WATCH", toJson(Watch{true})},
          {"BAR", toJson(fullBar())},
          {"PROGRESS", toJson(Progress{3, 9, "B1C3", 25, 108, 205.0})},
          {"STATE", toJson(State{RunState::kMeasuring, RunState::kPaused, "pause requested"})},
          {"PROMPT", toJson(fullPrompt())},
          {"SAMPLE", toJson(Sample{1, 10.0, 45.0, {1, 2, 3, 4, 5, 6}, 150.04, 0.0008, 25, 0.5})},
          {"EVENT", toJson(connectionCheck())},
          {"PLAN", toJson(fullPlan())},
          {"RESULT", toJson(fullResult())},
          {"RUNS", toJson(Runs{{{"2026-12-01T16-16-26", "done", ""}}})},
          {"MODELS", toJson(fullModels())},
          {"COMPENSATED", toJson(fullCompensated())},
          {"CHECK", toJson(fullCheck())},
          {"STATUS", toJson(fullStatus())}};
}

template <class T>
void roundTrips(const T& o) {
  INFO(T::kClass << " " << toJson(o).dump());
  const json j = toJson(o);
  CHECK(j.at("class") == T::kClass);
  const T back = parseObject<T>(j);
  CHECK(back == o);
  CHECK(toJson(back) == j);
  // And through the wire: one line, parsed back.
  const std::string line = frame(j);
  CHECK(line.find('\n') == line.size() - 1);
  CHECK(parseObject<T>(json::parse(line)) == o);
}

template <class T>
std::string parseError(const json& j) {
  try {
    parseObject<T>(j);
  } catch (const ObjectError& e) {
    return e.what();
  }
  return "(no error)";
}

json without(json j, const std::string& key) {
  j.erase(key);
  return j;
}
json with(json j, const std::string& key, json value) {
  j[key] = std::move(value);
  return j;
}

}  // namespace

TEST_CASE("objects: every server class round-trips through its struct") {
  roundTrips(Version{"0.1.0"});
  roundTrips(fullModels());
  roundTrips(Models{std::nullopt, {}});
  roundTrips(fullCompensated());
  roundTrips(fullCheck());
  roundTrips(Check{false, "no health check yet", "", 0, "", "", "", json::object()});
  roundTrips(Error{"no such run", std::nullopt, std::nullopt});
  roundTrips(Error{"2 safety violations", "start", {{"shell 3: joint 5 limit", "shell 4"}}});
  roundTrips(Ack{Cmd::kConfirm, std::nullopt});
  roundTrips(Ack{Cmd::kAbort, "run r1 (paused) is closed; nothing was moving"});
  roundTrips(Watch{false});
  roundTrips(fullBar());
  roundTrips(Bar{7, BarKind::kReading, -0.25, std::nullopt, 1});
  roundTrips(Bar{8, BarKind::kOverRange, std::nullopt, std::nullopt, 2});
  roundTrips(Bar{9, BarKind::kNoProbe, std::nullopt, std::nullopt, 3});
  roundTrips(Bar{10, BarKind::kDeviceError, std::nullopt, std::nullopt, 4});
  roundTrips(Progress{3, 9, "B1C3", 25, 108, 205.0});
  roundTrips(Progress{});
  roundTrips(State{RunState::kIdle, RunState::kChecking, "run r1: checking the plan"});
  roundTrips(State{RunState::kSolving, RunState::kDone, ""});
  roundTrips(fullPrompt());
  roundTrips(Prompt{PromptAction::kDetach, 0, std::nullopt, std::nullopt, std::nullopt,
                    "The run is complete: detach the ball-bar from the robot, then confirm."});
  roundTrips(Prompt{PromptAction::kDetach, 4, 2, 1, 0.0, "Detach the ball-bar, then confirm."});
  roundTrips(Sample{1, 10.0, 45.0, {1.5, -2, 3, 4, 5, 6.25}, 150.04, 0.0008, 25, 0.5});
  roundTrips(connectionCheck());
  roundTrips(Event{"nudged", {{"shell", 1}, {"mm", -1.25}}});
  roundTrips(Event{"set_complete", json::object()});
  roundTrips(fullPlan());
  roundTrips(fullResult());
  roundTrips(Result{false, "no fit yet", "", 0, 0, "", "", "", json::object()});
  roundTrips(Runs{});
  roundTrips(Runs{{{"r1", "done", ""}, {"r2", "interrupted", "daemon stopped"}}});
  roundTrips(fullStatus());
  roundTrips(Status{});
}

TEST_CASE("objects: STATUS always carries every field, null or empty when there is nothing") {
  const json s = toJson(Status{});
  for (const char* key :
       {"state", "reason", "run", "shell", "shells", "connection", "points_done", "points_total",
        "eta_s", "bar_attached", "devices", "bar", "prompt", "resumable", "clients", "plan"})
    CHECK(s.contains(key));
  CHECK(s["bar"].is_null());
  CHECK(s["prompt"].is_null());
  CHECK(s["plan"].is_null());
  CHECK(s["resumable"] == "");
  CHECK(s["devices"] == json{{"val", false}, {"bar", false}});
  // A STATE has its reason even when it is empty.
  CHECK(toJson(State{RunState::kIdle, RunState::kMoving, ""}).at("reason") == "");
}

TEST_CASE("objects: the open classes keep what is not typed") {
  // EVENT: every field but class and event is a detail.
  const Event e = parseObject<Event>({{"class", "EVENT"},
                                      {"event", "recentre"},
                                      {"shell", 2},
                                      {"step", -1},
                                      {"deflection_mm", 0.1}});
  CHECK(e.event == "recentre");
  CHECK(e.details == json{{"shell", 2}, {"step", -1}, {"deflection_mm", 0.1}});
  // RESULT: the run's fields are typed, `robocal solve --json`'s stay in fit.
  const Result r = parseObject<Result>(toJson(fullResult()));
  CHECK(r.fit.at("rms_mm") == 0.0299);
  CHECK_FALSE(r.fit.contains("run"));
  CHECK_FALSE(r.fit.contains("class"));
  const Result none =
      parseObject<Result>({{"class", "RESULT"}, {"available", false}, {"message", "no fit yet"}});
  CHECK_FALSE(none.available);
  CHECK(none.message == "no fit yet");
}

TEST_CASE("objects: the old builders are the structs' objects") {
  CHECK(versionObject("0.1.0") == toJson(Version{"0.1.0"}));
  CHECK(versionObject("0.1.0") == json{{"class", "VERSION"},
                                       {"release", "0.1.0"},
                                       {"proto_major", kProtoMajor},
                                       {"proto_minor", kProtoMinor}});
  CHECK(errorObject("bad") == json{{"class", "ERROR"}, {"message", "bad"}});
  CHECK(errorObject("bad", "start") == toJson(Error{"bad", "start", std::nullopt}));
  CHECK(ackObject(Cmd::kConfirm) == json{{"class", "ACK"}, {"cmd", "confirm"}});
  CHECK(ackObject(Cmd::kStart, "go") == toJson(Ack{Cmd::kStart, "go"}));
  CHECK(objectClass(json{{"class", "BAR"}}) == "BAR");
  CHECK(objectClass(json::array()) == "");
  for (const PromptAction a : {PromptAction::kConnect, PromptAction::kDetach})
    CHECK(parsePromptAction(promptActionName(a)) == a);
  for (const BarKind k :
       {BarKind::kReading, BarKind::kOverRange, BarKind::kNoProbe, BarKind::kDeviceError})
    CHECK(parseBarKind(barKindName(k)) == k);
  CHECK(parseCmd("nudge") == Cmd::kNudge);
  CHECK_FALSE(parseCmd("fly"));
}

TEST_CASE("objects: a malformed object is refused naming its class and field") {
  const json bar = toJson(fullBar());
  CHECK_THAT(parseError<Bar>(without(bar, "seq")), Contains("BAR: field 'seq' is missing"));
  CHECK_THAT(parseError<Bar>(with(bar, "seq", "5")),
             Contains("BAR: field 'seq' must be a whole number, got string"));
  CHECK_THAT(parseError<Bar>(with(bar, "kind", "sparks")),
             Contains("BAR: field 'kind' is \"sparks\", not one of reading, over_range"));
  CHECK_THAT(parseError<Bar>(with(bar, "deflection_mm", true)),
             Contains("BAR: field 'deflection_mm' must be a number, got boolean"));
  CHECK_THAT(parseError<Bar>(toJson(Progress{})), Contains("BAR: field 'class' is \"PROGRESS\""));
  CHECK_THAT(parseError<Bar>(without(bar, "class")), Contains("BAR: field 'class' is missing"));
  CHECK_THAT(parseError<Bar>(json::array()), Contains("BAR: expected a JSON object, got array"));

  const json status = toJson(fullStatus());
  CHECK_THAT(parseError<Status>(without(status, "resumable")),
             Contains("STATUS: field 'resumable' is missing"));
  CHECK_THAT(parseError<Status>(without(status, "plan")),
             Contains("STATUS: field 'plan' is missing"));
  CHECK_THAT(parseError<Status>(with(status, "state", "asleep")),
             Contains("STATUS: field 'state' is \"asleep\""));
  json devices = status["devices"];
  devices["val"] = "yes";
  CHECK_THAT(parseError<Status>(with(status, "devices", devices)),
             Contains("STATUS: field 'devices.val' must be true or false, got string"));
  CHECK_THAT(parseError<Status>(with(status, "devices", 1)),
             Contains("STATUS: field 'devices' must be an object"));
  CHECK_THAT(parseError<Status>(with(status, "bar", without(bar, "kind"))),
             Contains("STATUS: field 'bar' is not a BAR: BAR: field 'kind' is missing"));
  CHECK_THAT(parseError<Status>(with(status, "shell", 1.5)),
             Contains("STATUS: field 'shell' must be a whole number, got number"));

  const json prompt = toJson(fullPrompt());
  CHECK_THAT(parseError<Prompt>(without(prompt, "ball")),
             Contains("PROMPT: field 'ball' is missing"));
  CHECK_THAT(parseError<Prompt>(with(prompt, "action", "dance")),
             Contains("PROMPT: field 'action' is \"dance\", not one of connect, detach"));
  CHECK(parseError<Prompt>(with(without(prompt, "ball"), "action", "detach")) == "(no error)");

  CHECK_THAT(parseError<Runs>({{"class", "RUNS"},
                               {"runs",
                                {{{"run", "a"}, {"status", "done"}, {"reason", ""}},
                                 {{"run", "b"}, {"reason", ""}}}}}),
             Contains("RUNS: field 'runs[1].status' is missing"));
  CHECK_THAT(parseError<Runs>({{"class", "RUNS"}, {"runs", {1}}}),
             Contains("RUNS: field 'runs[0]' must be an object"));
  CHECK_THAT(parseError<Sample>(with(toJson(Sample{}), "joints", {1, "two"})),
             Contains("SAMPLE: field 'joints' must hold numbers, got string"));
  CHECK_THAT(parseError<Ack>({{"class", "ACK"}, {"cmd", "fly"}}),
             Contains("ACK: field 'cmd' is \"fly\""));
  CHECK_THAT(parseError<Error>({{"class", "ERROR"}, {"message", "x"}, {"violations", {2}}}),
             Contains("ERROR: field 'violations' must hold strings"));
  CHECK_THAT(parseError<Result>(without(toJson(fullResult()), "set")),
             Contains("RESULT: field 'set' is missing"));
  CHECK_THAT(parseError<Event>({{"class", "EVENT"}}), Contains("EVENT: field 'event' is missing"));
  CHECK_THAT(parseError<Plan>(with(toJson(fullPlan()), "points", nullptr)),
             Contains("PLAN: field 'points' is null"));
  // A STATE without reason is read as reason "" (daemons before the structs left it out).
  CHECK(parseObject<State>({{"class", "STATE"}, {"from", "idle"}, {"to", "checking"}}).reason ==
        "");
}

namespace {

// docs/protocol.md's "Server objects" table: class -> the text of its fields column.
std::map<std::string, std::string> documentedObjects() {
  const std::string doc = robocal::readTextFile(ROBOCAL_SOURCE_DIR "/docs/protocol.md");
  const auto begin = doc.find("## Server objects");
  REQUIRE(begin != std::string::npos);
  const auto end = doc.find("\n## ", begin + 1);
  const std::string section = doc.substr(begin, end - begin);
  std::map<std::string, std::string> rows;
  const std::regex row(R"(\n\| `([A-Z]+)` \|[^|\n]*\|([^\n]*)\|)");
  for (auto it = std::sregex_iterator(section.begin(), section.end(), row);
       it != std::sregex_iterator(); ++it)
    rows[(*it)[1]] = (*it)[2];
  return rows;
}

// The field names of an object, and of the parts it holds that are not objects of their own class
// (STATUS's devices, RUNS's entries); "class" itself is not a field.
void fieldNames(const json& j, std::set<std::string>& names) {
  if (j.is_array()) {
    for (const json& e : j) fieldNames(e, names);
    return;
  }
  if (!j.is_object()) return;
  for (const auto& [key, value] : j.items()) {
    if (key == "class") continue;
    names.insert(key);
    if (!(value.is_object() && value.contains("class"))) fieldNames(value, names);
  }
}

}  // namespace

TEST_CASE("objects: docs/protocol.md names every server class and every field the structs send") {
  const auto rows = documentedObjects();
  for (auto [cls, object] : fullObjects()) {
    INFO("class " << cls);
    REQUIRE(rows.count(cls) == 1);
    const std::string& doc_fields = rows.at(cls);
    // The open classes' details are documented by their own sources (events, robocal solve).
    if (cls == "EVENT") object = {{"event", object["event"]}};
    if (cls == "RESULT") object = toJson(Result{});
    if (cls == "CHECK") object["verdict"] = json::object();  // docs/health-check.md has its fields
    std::set<std::string> names;
    fieldNames(object, names);
    for (const std::string& name : names) {
      INFO("field " << name);
      CHECK(doc_fields.find("`" + name + "`") != std::string::npos);
    }
  }
  CHECK(rows.size() == fullObjects().size());
  // And the wire names of the enums, exactly as the table lists them: "`state` (idle, ...)".
  const auto listed = [&](const std::string& cls, const std::string& field) {
    std::smatch m;
    const std::string& text = rows.at(cls);
    REQUIRE(std::regex_search(text, m, std::regex("`" + field + "` \\(([a-z_, ]+)\\)")));
    std::set<std::string> names;
    const std::string list = m[1];
    const std::regex word("[a-z_]+");
    for (auto it = std::sregex_iterator(list.begin(), list.end(), word);
         it != std::sregex_iterator(); ++it)
      names.insert(it->str());
    return names;
  };
  std::set<std::string> states, kinds, actions;
  for (int s = 0; s <= static_cast<int>(RunState::kError); ++s)
    states.insert(runStateName(static_cast<RunState>(s)));
  for (const BarKind k :
       {BarKind::kReading, BarKind::kOverRange, BarKind::kNoProbe, BarKind::kDeviceError})
    kinds.insert(barKindName(k));
  for (const PromptAction a : {PromptAction::kConnect, PromptAction::kDetach})
    actions.insert(promptActionName(a));
  CHECK(listed("STATUS", "state") == states);
  CHECK(listed("BAR", "kind") == kinds);
  CHECK(listed("PROMPT", "action") == actions);
  // The unavailable RESULT's fields are documented too.
  std::set<std::string> names;
  fieldNames(toJson(Result{false, "no fit yet", "", 0, 0, "", "", "", {}}), names);
  for (const std::string& name : names) CHECK_THAT(rows.at("RESULT"), Contains("`" + name + "`"));
}
