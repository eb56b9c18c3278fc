#include <robocal/proto/objects.hpp>
#include <robocal/proto/protocol.hpp>

#include "wire_names.hpp"

#include <robocal/proto/objects.hpp>

#include <array>
#include <cmath>
#include <utility>

namespace robocal::proto {
namespace {

constexpr std::array<std::pair<Cmd, const char*>, 15> kCmds = {
    {{Cmd::kStatus, "status"},
     {Cmd::kNudge, "nudge"},
     {Cmd::kWatch, "watch"},
     {Cmd::kPlan, "plan"},
     {Cmd::kStart, "start"},
     {Cmd::kConfirm, "confirm"},
     {Cmd::kPause, "pause"},
     {Cmd::kResume, "resume"},
     {Cmd::kAbort, "abort"},
     {Cmd::kResult, "result"},
     {Cmd::kRuns, "runs"},
     {Cmd::kModels, "models"},
     {Cmd::kActivate, "activate"},
     {Cmd::kCompensate, "compensate"},
     {Cmd::kCheckResult, "check_result"}}};

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

// Six finite numbers at `where` (a key path for the message); nullopt when absent or null.
std::optional<std::array<double, 6>> sixNumbers(const json& obj, const char* key,
                                                const std::string& where, const std::string& cmd) {
  const auto it = obj.find(key);
  if (it == obj.end() || it->is_null()) return std::nullopt;
  if (!it->is_array() || it->size() != 6)
    throw RequestError(where + " must be an array of 6 numbers", cmd);
  std::array<double, 6> out{};
  for (std::size_t k = 0; k < 6; ++k) {
    if (!(*it)[k].is_number() || !std::isfinite((*it)[k].get<double>()))
      throw RequestError(where + "[" + std::to_string(k) + "] must be a finite number", cmd);
    out[k] = (*it)[k].get<double>();
  }
  return out;
}

std::vector<CompensateTarget> compensateTargets(const json& obj, const std::string& cmd) {
  const auto it = obj.find("targets");
  if (it == obj.end() || !it->is_array() || it->empty())
    throw RequestError(
        "compensate needs \"targets\": an array of {\"pose_mm_deg\": [x, y, z, rz, ry, rx]} or "
        "{\"joints_deg\": [j1, ..., j6]}, each with an optional \"name\"",
        cmd);
  if (it->size() > kMaxCompensateTargets)
    throw RequestError("compensate takes at most " + std::to_string(kMaxCompensateTargets) +
                           " targets a request, got " + std::to_string(it->size()),
                       cmd);
  std::vector<CompensateTarget> out;
  for (std::size_t i = 0; i < it->size(); ++i) {
    const json& t = (*it)[i];
    const std::string where = "targets[" + std::to_string(i) + "]";
    if (!t.is_object()) throw RequestError(where + " must be an object", cmd);
    CompensateTarget target;
    if (t.contains("name")) {
      if (!t["name"].is_string()) throw RequestError(where + ".name must be a string", cmd);
      target.name = t["name"].get<std::string>();
    }
    target.pose_mm_deg = sixNumbers(t, "pose_mm_deg", where + ".pose_mm_deg", cmd);
    target.joints_deg = sixNumbers(t, "joints_deg", where + ".joints_deg", cmd);
    if (target.pose_mm_deg.has_value() == target.joints_deg.has_value())
      throw RequestError(where + " needs one of \"pose_mm_deg\" and \"joints_deg\"", cmd);
    out.push_back(std::move(target));
  }
  return out;
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
    case Cmd::kModels:
    case Cmd::kCompensate:  // computes joints; moves nothing
    case Cmd::kCheckResult:
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
                           "result, runs, models, activate, compensate, check_result)",
                       name);
  req.token = stringField(obj, "token", name);
  switch (req.cmd) {
    case Cmd::kWatch:
      if (const json* v = field(obj, "enable", json::value_t::boolean, "true or false", name))
        req.watch_enable = v->get<bool>();
      break;
    case Cmd::kPlan:
    case Cmd::kStart:
      req.plan_path = stringField(obj, "plan", name);
      if (req.cmd == Cmd::kPlan) req.cell_path = stringField(obj, "cell", name);
      if (const json* v = field(obj, "check", json::value_t::boolean, "true or false", name))
        req.check = v->get<bool>();
      if (!req.plan_path.empty() && !req.cell_path.empty())
        throw RequestError("plan takes \"plan\" (load a file) or \"cell\" (make one), not both",
                           name);
      if (req.check && !req.cell_path.empty())
        throw RequestError("\"check\" plans from the configured cell: not with \"cell\"", name);
      if (req.check && !req.plan_path.empty())
        throw RequestError("\"check\" makes the health check's plan: not with \"plan\"", name);
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
    case Cmd::kActivate: {
      const json* v = field(obj, "version", json::value_t::number_integer, "a whole number", name);
      if (!v) throw RequestError("activate needs \"version\": the model's number (models)", name);
      req.model_version = v->get<int>();
      break;
    }
    case Cmd::kCompensate:
      req.targets = compensateTargets(obj, name);
      req.tool_mm_deg = sixNumbers(obj, "tool_mm_deg", "tool_mm_deg", name);
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
