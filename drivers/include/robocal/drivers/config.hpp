// Configuration of the serial drivers: where the ports are, how to open them, and the dialect of
// each device. Defaults are those of docs/drivers.md (the VAL II monitor and a generic LVDT gauge
// reader as described in hardware.md). JSON keys are the member names; units are in the names.
#pragma once

#include <nlohmann/json_fwd.hpp>

#include <array>
#include <string>
#include <vector>

namespace robocal::drivers {

struct SerialConfig {
  // A device path ("/dev/ttyUSB0", "/dev/serial/by-id/...", a pty or a symlink to one), or empty
  // to find the port by its USB serial number and/or description.
  std::string path;
  std::string usb_serial;       // exact USB serial number (libserialport enumeration)
  std::string usb_description;  // case-insensitive substring of description/product/manufacturer
  int baud = 9600;
  int data_bits = 8;
  std::string parity = "none";        // none | odd | even | mark | space
  int stop_bits = 1;                  // 1 | 2
  std::string flow_control = "none";  // none | xonxoff | rtscts
  // auto: ptys (and symlinks to ptys) with termios, real ports with libserialport.
  std::string opener = "auto";  // auto | libserialport | termios
  bool exclusive = true;        // refuse to share the port with another program
};

// The controller's dialect. `dialect` names a preset (valPreset: val2, vplus, kawasaki-as) whose
// values are the defaults of every other key; keys given in the file override them one by one.
struct ValConfig {
  SerialConfig serial;
  std::string dialect = "val2";
  // Every prompt the monitor shows. The first is the top-level one (VAL's "."); the others are
  // shown while a program or a DO instruction runs (VAL's "*"). Any of them ends a reply.
  std::vector<std::string> prompt = {".", "*"};
  std::string send_line_ending = "\r";
  // Command templates. {j1}..{j6} are joint angles (deg), {speed} the monitor speed (percent).
  std::string move_joints_command = "DO MOVE #PPOINT({j1},{j2},{j3},{j4},{j5},{j6})";
  std::string where_command = "WHERE";
  std::string speed_command = "SPEED {speed}";
  std::string abort_command = "ABORT";
  // Motion through vias without stopping (docs/cell-time.md; a guess at VAL II and V+ practice,
  // tried on robocal-cellsim only): the vias to the next point written as a program and executed,
  // the controller blending its consecutive MOVEs. Used when the plan's cell asks for it
  // (motion.through_vias); an empty path_execute_command means the dialect does not offer it and
  // every via is a DO MOVE that stops.
  std::string path_edit_command = "EDIT RCPATH";  // opens the program, emptied, for editing
  std::string path_move_line = "MOVE #PPOINT({j1},{j2},{j3},{j4},{j5},{j6})";  // one a step
  std::string path_end_edit = "E";                                             // leaves the editor
  std::string path_execute_command = "EXECUTE RCPATH";  // runs it; WHERE is answered meanwhile
  int joint_decimals = 3;
  // One capture: the controller's message. Lines matching it are errors. The message must
  // start with a character other than '*' or a space: a bare "*" is VAL's busy prompt.
  std::string error_regex = R"(^\s*\*+\s*([^*\s].*?)\s*\*?\s*$)";
  // Severity of an error message, highest first; the most severe error line of a reply is the
  // one raised.
  std::string power_off_regex = "POWER OFF|POWER IS OFF|E-?STOP|EMERGENCY";
  std::string out_of_range_regex = "OUT OF RANGE|OUT OF MOTION RANGE|LIMIT|UNREACHABLE";
  // Lines the controller prints on its own that are neither replies nor errors (a DO motion's
  // completion): dropped wherever they come, counted in ValStats::ignored_lines. Empty: none.
  std::string ignore_regex = R"(^\s*(DO MOTION COMPLETED|PROGRAM COMPLETED)\b.*$)";
  // Text left without a line ending that asks something ("Initialize?", "(Y/N)?", "CHANGE?"):
  // the reply ends there and the driver raises QuestionError. It never answers on its own.
  std::string question_regex = R"(\?\s*$)";
  bool where_joints_first = false;  // how the simulator prints WHERE (the parser reads either)
  std::vector<std::string> location_headers = {"X", "Y", "Z", "O", "A", "T"};
  std::vector<std::string> joint_headers = {"JT1", "JT2", "JT3", "JT4", "JT5", "JT6"};
  // Per-command timeouts (until the prompt is back).
  double connect_timeout_s = 3.0;
  double command_timeout_s = 2.0;
  double where_timeout_s = 2.0;
  // A move command's deadline: this margin plus the move's largest joint change at the slowest
  // joint speed (below) scaled by the current SPEED, so that a controller whose DO MOVE returns
  // its prompt only when the motion ends has the time it needs. Past it, while the arm still
  // moves, the driver goes on watching WHERE rather than failing.
  double move_timeout_s = 5.0;
  double slowest_joint_speed_deg_s = 20;  // at SPEED 100: the slowest joint's top speed
  double abort_timeout_s = 2.0;
  // Motion completion: poll WHERE until at the target and still.
  double poll_interval_s = 0.1;
  double at_target_tol_deg = 0.05;
  double still_tol_deg = 0.005;
  int still_polls = 2;            // consecutive unchanged polls that make "still"
  double motion_timeout_s = 120;  // whole move, command to still at target
  double stopped_short_s = 3.0;   // still but not at target this long: the arm was stopped
  int where_retries = 2;          // unreadable WHERE replies in a row tolerated during a move
};

// The dialect presets: a ValConfig with a preset's defaults (serial settings untouched).
// ConfigError naming the preset list for an unknown name.
ValConfig valPreset(const std::string& dialect);
std::vector<std::string> valPresetNames();

struct BarConfig {
  SerialConfig serial;
  // Line format preset: mm_suffix ("+0.01234 MM"), mitutoyo ("01A+000.1234"),
  // gn ("GN01,+0016.2345"). It sets the default value_regex; the simulator prints it.
  std::string format = "mm_suffix";
  std::string value_regex;     // one capture, the value; empty = the preset's
  double unit_scale_mm = 1.0;  // mm per unit of the captured value
  bool ignore_case = true;
  std::string over_range_regex = R"((OVER|UNDER)[ _-]?RANGE)";
  std::string no_probe_regex = R"(NO[ _-]?PROBE)";
  std::string error_regex = R"(^\s*(ERR|ERROR)\b)";
  std::string mode = "polled";  // polled | streamed
  std::string poll_command = "?";
  std::string send_line_ending = "\r";
  double poll_timeout_s = 0.5;  // one poll's answer
  double stale_after_s = 2.0;   // no valid reading this long: stale
  double range_mm = 0;          // |value| past this is over range (0 = only the reader says)
};

struct DriversConfig {
  ValConfig val;
  BarConfig bar;
};

// Presets of bar line formats (name, regex with one capture).
std::string barPresetRegex(const std::string& format);
std::vector<std::string> barPresetNames();

// Parsing: unknown keys and wrong types are ConfigError naming the key path and `source`
// ("drivers.json: val.serial.baud: expected a number"). Missing keys keep their defaults.
SerialConfig serialConfigFromJson(const nlohmann::json& json, const std::string& where);
ValConfig valConfigFromJson(const nlohmann::json& json, const std::string& where = "val");
BarConfig barConfigFromJson(const nlohmann::json& json, const std::string& where = "bar");
DriversConfig driversConfigFromJson(const nlohmann::json& json, const std::string& source);
// The text of a drivers configuration file; `source` names it in errors. ConfigError.
DriversConfig parseDriversConfig(const std::string& text, const std::string& source);
DriversConfig loadDriversConfig(const std::string& path);
// The same from either a drivers configuration or robocald's configuration file (an object with
// a "model" or "drivers" key, docs/robocald.md): of the daemon's file, its "drivers" section as
// the daemon reads it (defaults when it has none); its other keys are the daemon's to check.
// ConfigError, naming `source` (and "drivers" for the daemon's file) and the key.
DriversConfig parseDriversOrDaemonConfig(const std::string& text, const std::string& source);
DriversConfig loadDriversOrDaemonConfig(const std::string& path);
// Checks values (regexes compile, templates name known fields, numbers in range); ConfigError.
void validate(const ValConfig& config, const std::string& where = "val");
void validate(const BarConfig& config, const std::string& where = "bar");

nlohmann::json toJson(const SerialConfig& config);
nlohmann::json toJson(const ValConfig& config);
nlohmann::json toJson(const BarConfig& config);
nlohmann::json toJson(const DriversConfig& config);

}  // namespace robocal::drivers
