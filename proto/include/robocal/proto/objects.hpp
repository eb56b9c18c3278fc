// robocald's server objects (docs/protocol.md, "Server objects"), one typed struct per class.
// The daemon builds its objects with toJson(X{...}); clients read them with parseObject<X>(json).
// Field names, which fields are always present and the wire spelling of the enums are defined
// here once: the daemon and the command line cannot drift apart, and tests/daemon/test_objects.cpp
// checks the structs against the documentation's table.
//
// Conventions:
//  - toJson emits "class" and every field; a std::optional field is left out when empty, except
//    where the documentation says the field is always present (STATUS's `bar`, `prompt`, `plan`:
//    null when none).
//  - parseObject<X> checks "class" and every field's presence and type, and throws ObjectError
//    naming the class and the field ("STATUS: field 'devices.val' must be true or false, got
//    string"). Fields it does not know are ignored, except in the open-ended EVENT and RESULT,
//    which keep them (Event::details, Result::fit).
#pragma once

#include <robocal/proto/protocol.hpp>

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace robocal::proto {

// A server object that is not what its class says: the message names the class and the field.
class ObjectError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A PROMPT's `action`, as spelled on the wire.
enum class PromptAction { kConnect, kDetach };
const char* promptActionName(PromptAction action);
std::optional<PromptAction> parsePromptAction(std::string_view name);
// The BAR kind with this wire name; nullopt for an unknown name.
std::optional<BarKind> parseBarKind(std::string_view name);
// The command with this wire name; nullopt for an unknown name.
std::optional<Cmd> parseCmd(std::string_view name);

// The "class" of a server object; "" when it has none (or is not an object).
std::string objectClass(const nlohmann::json& object);

// VERSION: the greeting on connect.
struct Version {
  static constexpr const char* kClass = "VERSION";
  std::string release;
  int proto_major = kProtoMajor;
  int proto_minor = kProtoMinor;
  bool operator==(const Version&) const = default;
};

// ERROR: a refused request or a fault. `cmd` is the request's cmd when known (a string: an unknown
// command is named as sent); `violations` lists a plan's safety violations.
struct Error {
  static constexpr const char* kClass = "ERROR";
  std::string message;
  std::optional<std::string> cmd;
  std::optional<std::vector<std::string>> violations;
  bool operator==(const Error&) const = default;
};

// ACK: a request done; `message` says what happens next when there is something to say.
struct Ack {
  static constexpr const char* kClass = "ACK";
  Cmd cmd = Cmd::kStatus;
  std::optional<std::string> message;
  bool operator==(const Ack&) const = default;
};

// WATCH: the reply to `watch`.
struct Watch {
  static constexpr const char* kClass = "WATCH";
  bool enable = true;
  bool operator==(const Watch&) const = default;
};

// BAR: one line of the ball-bar reader. Only a reading has `deflection_mm`, and `length_mm` only
// with a bar attached.
struct Bar {
  static constexpr const char* kClass = "BAR";
  std::uint64_t seq = 0;
  BarKind kind = BarKind::kReading;
  std::optional<double> deflection_mm;
  std::optional<double> length_mm;
  std::int64_t t_us = 0;  // CLOCK_MONOTONIC of the line's arrival
  bool operator==(const Bar&) const = default;
};

// PROGRESS: where the run is; `eta_s` is the robot time left.
struct Progress {
  static constexpr const char* kClass = "PROGRESS";
  int shell = 0;
  int shells = 0;
  std::string connection;  // e.g. "B1C3"; "" before the first shell
  int points_done = 0;
  int points_total = 0;
  double eta_s = 0;
  bool operator==(const Progress&) const = default;
};

// STATE: a change of the run state. `reason` is always sent ("" when there is none); parseObject
// reads a STATE without it as reason "" (daemons before proto/objects.hpp leave it out when empty).
struct State {
  static constexpr const char* kClass = "STATE";
  RunState from = RunState::kIdle;
  RunState to = RunState::kIdle;
  std::string reason;
  bool operator==(const State&) const = default;
};

// PROMPT: the operator must connect or detach the bar. A connect prompt always names ball, chuck
// and extension; a detach prompt names them when the daemon knows them. `shell` 0 is the detach
// at the end of a run.
struct Prompt {
  static constexpr const char* kClass = "PROMPT";
  PromptAction action = PromptAction::kConnect;
  int shell = 0;
  std::optional<int> ball;   // 1-based
  std::optional<int> chuck;  // 1-based
  std::optional<double> extension_mm;
  std::string message;
  bool operator==(const Prompt&) const = default;
};

// SAMPLE: one data point, sent once it is on disk.
struct Sample {
  static constexpr const char* kClass = "SAMPLE";
  int shell = 0;
  double lat_deg = 0;
  double lon_deg = 0;
  std::vector<double> joints;  // deg, the robot's six joints where it measured
  double length_mm = 0;
  double spread_mm = 0;
  int readings = 0;
  double dwell_s = 0;
  bool operator==(const Sample&) const = default;
};

// EVENT: open-ended. `event` names it; `details` holds every other field of the object (e.g. for
// "connection_check": shell, connection, steps [{commanded_mm, reading_change_mm}], ok; for
// "nudged": shell, mm). toJson merges details into the object; parseObject puts every field but
// "class" and "event" there.
struct Event {
  static constexpr const char* kClass = "EVENT";
  std::string event;
  nlohmann::json details = nlohmann::json::object();
  bool operator==(const Event&) const = default;
};

// PLAN: the summary of the plan the daemon made or loaded.
struct Plan {
  static constexpr const char* kClass = "PLAN";
  std::string source;  // the plan or cell file it came from
  int shells = 0;
  int points = 0;
  int vias = 0;
  int dropped = 0;
  double duration_s = 0;
  int rank = 0;
  double condition_number = 0;
  double max_deviation_mm = 0;
  double predicted_deflection_mm = -1;  // worst over shells; < 0: not computed
  double predicted_change_mm = -1;      // from the connect pose's reading, worst over shells
  // The calibrated model's predicted RMS tool position error where the user works (the cell's
  // work volume) and over the arm's whole range (a check plan is not fitted: < 0, as for a
  // plan file that does not say).
  double predicted_work_volume_error_mm = -1;
  double predicted_whole_range_error_mm = -1;
  bool operator==(const Plan&) const = default;
};

// RESULT: open-ended. With a fit, the typed fields are the ones the daemon adds (the run's) and
// `fit` holds the rest of the object: `robocal solve --json` of the run's samples (n, rank,
// rms_mm, problems, parameter_table, shells, validation_*, ...) and `prediction`. Before the
// first fit the object is {"available": false, "message": ...} and the run fields are empty.
struct Result {
  static constexpr const char* kClass = "RESULT";
  bool available = true;
  std::string message;  // available == false only
  std::string run;
  int set = 0;
  double extension_mm = 0;
  std::string calibrated_file;
  std::string report_dir;
  std::string samples_file;
  nlohmann::json fit = nlohmann::json::object();
  bool operator==(const Result&) const = default;
};

// RUNS: every run the daemon keeps, with its status (running, interrupted, paused, aborted,
// done, ...) and the reason of the last change.
struct RunEntry {
  std::string run;
  std::string status;
  std::string reason;
  bool operator==(const RunEntry&) const = default;
};
struct Runs {
  static constexpr const char* kClass = "RUNS";
  std::vector<RunEntry> runs;
  bool operator==(const Runs&) const = default;
};

// MODELS: the calibrated models the daemon keeps (docs/protocol.md, "Models"), oldest first.
// Each is an immutable file; `active` is the version compensate uses (null: none activated).
struct HealthCheckEntry {
  std::string run;
  std::string date_utc;
  std::string verdict;  // pass, warn, fail
  double rms_mm = 0;    // bar residual RMS the model predicted at the check's samples
  bool operator==(const HealthCheckEntry&) const = default;
};
struct ModelEntry {
  int version = 0;
  std::string file;
  std::string date_utc;
  std::string run;
  int set = 0;
  int samples = 0;
  double fit_rms_mm = 0;
  int rank = 0;
  bool usable = true;                 // no problems: it may be activated
  std::vector<std::string> problems;  // why not, when not
  // Predicted 1-sigma tool position error over the cell's work volume (RMS), when known.
  std::optional<double> work_volume_error_mm;
  std::vector<HealthCheckEntry> checks;
  bool active = false;
  bool operator==(const ModelEntry&) const = default;
};
struct Models {
  static constexpr const char* kClass = "MODELS";
  std::optional<int> active;  // always sent; null when none is active
  std::vector<ModelEntry> models;
  bool operator==(const Models&) const = default;
};

// COMPENSATED: the answer to compensate, one row per target in the request's order, the fields of
// `robocal compensate`'s CSV (docs/compensation.md); joints only when the status allows them.
struct CompensatedRow {
  std::string name;
  std::string
      status;  // ok, unreachable, near_singularity, outside_limits, outside_measured, no_gain
  std::string config;
  std::string note;
  std::optional<std::array<double, 6>> joints_deg;
  std::optional<double> predicted_error_mm;
  // Where to come from: the approach pre-point, below the target in every joint, when the
  // calibration reached its points that way (docs/compensation.md, "The approach").
  std::optional<std::array<double, 6>> pre_point_joints_deg;
  bool operator==(const CompensatedRow&) const = default;
};
struct Compensated {
  static constexpr const char* kClass = "COMPENSATED";
  int model = 0;  // the active model's version
  std::vector<CompensatedRow> targets;
  bool operator==(const Compensated&) const = default;
};

// CHECK: a health check's verdict (docs/health-check.md), at the end of a check run and in reply
// to check_result. `verdict` holds the verdict's fields (status, rms_mm, rms_ratio, moved, ...),
// `text` the same for a person. Before the first check only `available` (false) and `message`.
struct Check {
  static constexpr const char* kClass = "CHECK";
  bool available = true;
  std::string message;  // available == false only
  std::string run;
  int model_version = 0;
  std::string date_utc;
  std::string status;  // pass, warn, fail
  std::string text;
  nlohmann::json verdict = nlohmann::json::object();
  bool operator==(const Check&) const = default;
};

// STATUS: every field is always present. `devices` has val_error / bar_error while that device is
// not connected; `bar`, `prompt` and `plan` are null when there is none.
struct Devices {
  bool val = false;
  bool bar = false;
  std::optional<std::string> val_error;
  std::optional<std::string> bar_error;
  bool operator==(const Devices&) const = default;
};
// What the daemon's client side has had to do since it started (ClientHub): connections refused
// (too many), closed as stuck, closed for an unfinished request line, BAR lines dropped for slow
// clients.
struct ClientCounts {
  std::int64_t refused = 0;
  std::int64_t stalled = 0;
  std::int64_t timed_out = 0;
  std::int64_t dropped_lines = 0;
  bool operator==(const ClientCounts&) const = default;
};
struct Status {
  static constexpr const char* kClass = "STATUS";
  RunState state = RunState::kIdle;
  std::string reason;
  std::string run;  // "" when none
  int shell = 0;
  int shells = 0;
  std::string connection;
  int points_done = 0;
  int points_total = 0;
  double eta_s = 0;
  bool bar_attached = false;
  Devices devices;
  std::optional<Bar> bar;        // the latest BAR
  std::optional<Prompt> prompt;  // the pending PROMPT
  std::string resumable;         // a paused or interrupted run's id, "" when none
  int clients = 0;
  ClientCounts client_counts;
  std::optional<Plan> plan;  // the daemon's current PLAN
  bool operator==(const Status&) const = default;
  // The progress part of a STATUS, as a PROGRESS object would carry it.
  Progress progress() const {
    return {shell, shells, connection, points_done, points_total, eta_s};
  }
};

nlohmann::json toJson(const Version& o);
nlohmann::json toJson(const Error& o);
nlohmann::json toJson(const Ack& o);
nlohmann::json toJson(const Watch& o);
nlohmann::json toJson(const Bar& o);
nlohmann::json toJson(const Progress& o);
nlohmann::json toJson(const State& o);
nlohmann::json toJson(const Prompt& o);
nlohmann::json toJson(const Sample& o);
nlohmann::json toJson(const Event& o);
nlohmann::json toJson(const Plan& o);
nlohmann::json toJson(const Result& o);
nlohmann::json toJson(const Runs& o);
nlohmann::json toJson(const Status& o);
nlohmann::json toJson(const Models& o);
nlohmann::json toJson(const Compensated& o);
nlohmann::json toJson(const Check& o);

// The object as a T; ObjectError naming the class and field when it is not one.
template <class T>
T parseObject(const nlohmann::json& object);

template <>
Version parseObject<Version>(const nlohmann::json& object);
template <>
Error parseObject<Error>(const nlohmann::json& object);
template <>
Ack parseObject<Ack>(const nlohmann::json& object);
template <>
Watch parseObject<Watch>(const nlohmann::json& object);
template <>
Bar parseObject<Bar>(const nlohmann::json& object);
template <>
Progress parseObject<Progress>(const nlohmann::json& object);
template <>
State parseObject<State>(const nlohmann::json& object);
template <>
Prompt parseObject<Prompt>(const nlohmann::json& object);
template <>
Sample parseObject<Sample>(const nlohmann::json& object);
template <>
Event parseObject<Event>(const nlohmann::json& object);
template <>
Plan parseObject<Plan>(const nlohmann::json& object);
template <>
Result parseObject<Result>(const nlohmann::json& object);
template <>
Runs parseObject<Runs>(const nlohmann::json& object);
template <>
Status parseObject<Status>(const nlohmann::json& object);
template <>
Models parseObject<Models>(const nlohmann::json& object);
template <>
Compensated parseObject<Compensated>(const nlohmann::json& object);
template <>
Check parseObject<Check>(const nlohmann::json& object);

}  // namespace robocal::proto
