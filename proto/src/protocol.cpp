#include <robocal/proto/objects.hpp>
#include <robocal/proto/protocol.hpp>

#include "wire_names.hpp"

#include <robocal/proto/objects.hpp>

#include <array>
#include <cmath>
#include <utility>

namespace robocal::proto {
namespace {

constexpr std::array<std::pair<Cmd, const char*>, 11> kCmds = {{{Cmd::kStatus, "status"},
                                                                {Cmd::kNudge, "nudge"},
                                                                {Cmd::kWatch, "watch"},
                                                                {Cmd::kPlan, "plan"},
                                                                {Cmd::kStart, "start"},
                                                                {Cmd::kConfirm, "confirm"},
                                                                {Cmd::kPause, "pause"},
                                                                {Cmd::kResume, "resume"},
                                                                {Cmd::kAbort, "abort"},
                                                                {Cmd::kResult, "result"},
                                                                {Cmd::kRuns, "runs"}}};

using json = nlohmann::json;

const json* field(const json& obj, const char* key, json::value_t type, const char* type_name,
                  const std::string& cmd) {
  const auto it = obj.find(key);
  if (it == obj.end() || it->is_null()) return nullptr;
  const bool ok = type == json::value_t::number_integer
                      ? it->is_number_integer()
                      : (type == json::value_t::boolean ? it->is_boolean() : it->is_string());
  if (!ok)
    throw RequestError("field '" + std::string(key) + "' of " + cmd + " must be " + type_name +
                           ", got " + it->type_name(),
                       cmd);
  return &*it;
}

std::string stringField(const json& obj, const char* key, const std::string& cmd) {
  const json* v = field(obj, key, json::value_t::string, "a string", cmd);
  return v ? v->get<std::string>() : std::string();
}

}  // namespace

const char* cmdName(Cmd cmd) {
  return wireName(kCmds, cmd, "?");
}

bool needsToken(Cmd cmd) {
  switch (cmd) {
    case Cmd::kStatus:
    case Cmd::kWatch:
    case Cmd::kResult:
    case Cmd::kRuns:
      return false;
    default:
      return true;
  }
}

Request parseRequest(std::string_view line) {
  json obj;
  try {
    obj = json::parse(line);
  } catch (const json::exception& e) {
    throw RequestError(std::string("not valid JSON: ") + e.what());
  }
  if (!obj.is_object())
    throw RequestError(std::string("a request must be a JSON object, got ") + obj.type_name());
  const auto cmd_it = obj.find("cmd");
  if (cmd_it == obj.end()) throw RequestError("request has no \"cmd\"");
  if (!cmd_it->is_string()) throw RequestError("\"cmd\" must be a string");
  const std::string name = cmd_it->get<std::string>();
  Request req;
  const std::optional<Cmd> cmd = parseCmd(name);
  if (cmd) req.cmd = *cmd;
  if (!cmd)
    throw RequestError("unknown cmd \"" + name +
                           "\" (status, watch, plan, start, confirm, nudge, pause, resume, abort, "
                           "result, runs)",
                       name);
  req.token = stringField(obj, "token", name);
  switch (req.cmd) {
    case Cmd::kWatch:
      if (const json* v = field(obj, "enable", json::value_t::boolean, "true or false", name))
        req.watch_enable = v->get<bool>();
      break;
    case Cmd::kPlan:
      req.plan_path = stringField(obj, "plan", name);
      req.cell_path = stringField(obj, "cell", name);
      if (!req.plan_path.empty() && !req.cell_path.empty())
        throw RequestError("plan takes \"plan\" (load a file) or \"cell\" (make one), not both",
                           name);
      break;
    case Cmd::kStart:
      req.plan_path = stringField(obj, "plan", name);
      break;
    case Cmd::kConfirm:
      if (const json* v =
              field(obj, "shell", json::value_t::number_integer, "a whole number", name))
        req.shell = v->get<int>();
      break;
    case Cmd::kNudge: {
      const auto it = obj.find("mm");
      if (it == obj.end() || !it->is_number())
        throw RequestError("nudge needs \"mm\": a number (mm along the bar, + away from the chuck)",
                           name);
      req.nudge_mm = it->get<double>();
      if (!std::isfinite(req.nudge_mm)) throw RequestError("nudge \"mm\" must be finite", name);
      if (const json* v =
              field(obj, "shell", json::value_t::number_integer, "a whole number", name))
        req.shell = v->get<int>();
      break;
    }
    case Cmd::kResume:
      req.run_id = stringField(obj, "run", name);
      break;
    case Cmd::kPause:
    case Cmd::kAbort:
      req.reason = stringField(obj, "reason", name);
      break;
    default:
      break;
  }
  return req;
}

std::string frame(const json& object) {
  // Invalid UTF-8 from a client echoed back must not throw: replace it.
  return object.dump(-1, ' ', false, json::error_handler_t::replace) + "\n";
}

json versionObject(const std::string& release) {
  return toJson(Version{release});
}

json errorObject(const std::string& message, const std::string& cmd) {
  return toJson(Error{message, cmd.empty() ? std::nullopt : std::optional<std::string>(cmd), {}});
}

const char* barKindName(BarKind kind) {
  switch (kind) {
    case BarKind::kReading:
      return "reading";
    case BarKind::kOverRange:
      return "over_range";
    case BarKind::kNoProbe:
      return "no_probe";
    case BarKind::kDeviceError:
      return "device_error";
  }
  return "device_error";
}

namespace {
constexpr std::array<std::pair<RunState, const char*>, 11> kRunStates = {
    {{RunState::kIdle, "idle"},
     {RunState::kChecking, "checking"},
     {RunState::kMoving, "moving"},
     {RunState::kAwaitingConfirm, "awaiting_confirm"},
     {RunState::kMeasuring, "measuring"},
     {RunState::kPaused, "paused"},
     {RunState::kInterrupted, "interrupted"},
     {RunState::kSolving, "solving"},
     {RunState::kDone, "done"},
     {RunState::kAborted, "aborted"},
     {RunState::kError, "error"}}};
}  // namespace

const char* runStateName(RunState state) {
  return wireName(kRunStates, state, "error");
}

std::optional<RunState> parseRunState(std::string_view name) {
  return wireValue(kRunStates, name);
}

std::optional<Cmd> parseCmd(std::string_view name) {
  return wireValue(kCmds, name);
}

bool isBusy(RunState state) {
  return state == RunState::kChecking || state == RunState::kMoving ||
         state == RunState::kAwaitingConfirm || state == RunState::kMeasuring;
}

json ackObject(Cmd cmd, const std::string& message) {
  return toJson(Ack{cmd, message.empty() ? std::nullopt : std::optional<std::string>(message)});
}

}  // namespace robocal::proto
