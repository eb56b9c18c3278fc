// robocald's client protocol (docs/protocol.md): newline-delimited JSON objects over TCP, in the
// manner of gpsd. The server greets with a VERSION object; every server object has a "class";
// every request has a "cmd". This module knows only the wire format: parsing and validating
// requests, and building the server's objects (objects.hpp: one struct per class). No sockets.
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace robocal::proto {

inline constexpr int kProtoMajor = 1;
inline constexpr int kProtoMinor = 0;
inline constexpr std::size_t kDefaultMaxLineBytes = 16 * 1024;

enum class Cmd {
  kStatus,
  kWatch,
  kPlan,
  kStart,
  kConfirm,
  kNudge,
  kPause,
  kResume,
  kAbort,
  kResult,
  kRuns,
  kModels,
  kActivate,
  kCompensate,
  kCheckResult
};
const char* cmdName(Cmd cmd);

// A request that cannot be served as sent. The message says what is wrong and where.
class RequestError : public std::runtime_error {
 public:
  RequestError(const std::string& what, std::string cmd = {})
      : std::runtime_error(what), cmd_(std::move(cmd)) {}
  const std::string& cmd() const { return cmd_; }

 private:
  std::string cmd_;
};

// One target of a compensate request: a desired tool pose [x_mm, y_mm, z_mm, rz_deg, ry_deg,
// rx_deg] in the chuck fixture's frame, or a program's nominal joint readings (deg).
struct CompensateTarget {
  std::string name;
  std::optional<std::array<double, 6>> pose_mm_deg;
  std::optional<std::array<double, 6>> joints_deg;
  bool operator==(const CompensateTarget&) const = default;
};
inline constexpr std::size_t kMaxCompensateTargets = 1000;

struct Request {
  Cmd cmd = Cmd::kStatus;
  std::string token;  // "" when not given
  // Command fields (validated by parseRequest):
  bool watch_enable = true;  // watch
  std::string plan_path;     // plan (a plan file to load) and start (optional)
  bool check = false;        // plan, start: the health check's plan (docs/health-check.md)
  std::string cell_path;     // plan: plan from this cell file instead of the configured one
  std::optional<int> shell;  // confirm, nudge: the shell of the pending prompt (must match)
  double nudge_mm = 0;       // nudge: move the ball this far along the bar (+: away from the chuck)
  std::string run_id;        // resume: an interrupted run to continue (default: the latest)
  std::string reason;        // pause / abort: the operator's words, for the log
  int model_version = 0;     // activate: the model to make active
  std::vector<CompensateTarget> targets;             // compensate
  std::optional<std::array<double, 6>> tool_mm_deg;  // compensate: TCP in the ball fixture frame
};

// Parses one line (without its newline). RequestError on malformed JSON, a non-object, a missing
// or unknown cmd, or a field of the wrong type.
Request parseRequest(std::string_view line);

// Commands that move the robot or change the run need the token.
bool needsToken(Cmd cmd);

// Server objects. frame() turns one into a wire line (compact JSON and '\n').
std::string frame(const nlohmann::json& object);
nlohmann::json versionObject(const std::string& release);
nlohmann::json errorObject(const std::string& message, const std::string& cmd = {});
nlohmann::json ackObject(Cmd cmd, const std::string& message = {});

// A BAR object's `kind`, as spelled on the wire (docs/protocol.md). Only a reading carries
// `deflection_mm` (and `length_mm` with a bar attached).
enum class BarKind { kReading, kOverRange, kNoProbe, kDeviceError };
const char* barKindName(BarKind kind);

// The daemon's run state (STATUS `state`, STATE `from`/`to`), spelled once here.
enum class RunState {
  kIdle,
  kChecking,         // planning or checking a plan before a run
  kMoving,           // the robot is moving (to a connect pose, between points)
  kAwaitingConfirm,  // a PROMPT waits for the operator; the robot is still
  kMeasuring,        // dwelling and reading the bar at points
  kPaused,           // stopped by a fault or the operator; resume continues
  kInterrupted,      // the daemon stopped during a run; resume continues
  kSolving,          // fitting a completed shell set
  kDone,
  kAborted,
  kError
};
const char* runStateName(RunState state);
// The state with this wire name; nullopt for an unknown name.
std::optional<RunState> parseRunState(std::string_view name);
// A run owns the robot in these states: a new start or resume is refused.
bool isBusy(RunState state);

}  // namespace robocal::proto
