#include <robocal/drivers/config.hpp>
#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/protocol.hpp>
#include <robocal/jsonread/strict_json.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

namespace robocal::drivers {
namespace {

using nlohmann::json;

// The drivers' sections, each read with its path as the source ("val.serial"); the caller
// (driversConfigFromJson) names the file.
using ObjectReader = jsonread::Object<ConfigError>;
ObjectReader objectReader(const json& object, const std::string& where) {
  return ObjectReader(jsonread::Reader<ConfigError>(""), object, where);
}

void checkRegex(const std::string& pattern, const std::string& key, int min_captures) {
  try {
    std::regex re(pattern);
    if (static_cast<int>(re.mark_count()) < min_captures)
      throw ConfigError(key + ": the regular expression needs " + std::to_string(min_captures) +
                        " capture group (...) around the value");
  } catch (const std::regex_error& e) {
    throw ConfigError(key + ": not a valid regular expression (" + e.what() + "): " + pattern);
  }
}

void checkPositive(double value, const std::string& key) {
  if (!(value > 0)) throw ConfigError(key + ": must be greater than 0");
}

}  // namespace

std::vector<std::string> barPresetNames() {
  return {"mm_suffix", "mitutoyo", "gn"};
}

std::string barPresetRegex(const std::string& format) {
  if (format == "mm_suffix") return R"(^\s*([+-]?\d+(?:\.\d*)?)\s*MM\s*$)";
  if (format == "mitutoyo") return R"(^\s*01A([+-]\d+(?:\.\d*)?)\s*$)";
  if (format == "gn") return R"(^\s*GN\d+,([+-]?\d+(?:\.\d*)?)\s*$)";
  throw ConfigError("bar.format: unknown format '" + format + "' (mm_suffix, mitutoyo or gn)");
}

SerialConfig serialConfigFromJson(const json& j, const std::string& where) {
  SerialConfig c;
  ObjectReader r = objectReader(j, where);
  r.get("path", c.path);
  r.get("usb_serial", c.usb_serial);
  r.get("usb_description", c.usb_description);
  r.get("baud", c.baud);
  r.get("data_bits", c.data_bits);
  r.get("parity", c.parity);
  r.get("stop_bits", c.stop_bits);
  r.get("flow_control", c.flow_control);
  r.get("opener", c.opener);
  r.get("exclusive", c.exclusive);
  r.finish();
  if (c.baud <= 0) throw ConfigError(where + ".baud: must be a positive baud rate like 9600");
  if (c.data_bits < 5 || c.data_bits > 8) throw ConfigError(where + ".data_bits: must be 5 to 8");
  static const std::set<std::string> parities{"none", "odd", "even", "mark", "space"};
  if (!parities.count(c.parity))
    throw ConfigError(where + ".parity: must be none, odd, even, mark or space");
  if (c.stop_bits != 1 && c.stop_bits != 2) throw ConfigError(where + ".stop_bits: must be 1 or 2");
  if (c.flow_control != "none" && c.flow_control != "xonxoff" && c.flow_control != "rtscts")
    throw ConfigError(where + ".flow_control: must be none, xonxoff or rtscts");
  if (c.opener != "auto" && c.opener != "libserialport" && c.opener != "termios")
    throw ConfigError(where + ".opener: must be auto, libserialport or termios");
  return c;
}

std::vector<std::string> valPresetNames() {
  return {"val2", "vplus", "kawasaki-as"};
}

ValConfig valPreset(const std::string& dialect) {
  ValConfig c;  // val2: the member defaults
  c.dialect = dialect;
  if (dialect == "val2") return c;
  if (dialect == "vplus") {
    // Adept V+ hosts end commands with CR LF and read up to the "." prompt (hardware.md).
    c.send_line_ending = "\r\n";
    return c;
  }
  if (dialect == "kawasaki-as") {
    // Kawasaki AS (hardware.md, "descendant (AS)"): prompt ">", JMOVE, "(P1000)..." error lines,
    // WHERE with the joint block first and units in the location headers.
    c.prompt = {">"};
    c.move_joints_command = "DO JMOVE #PPOINT({j1},{j2},{j3},{j4},{j5},{j6})";
    // AS blends in a program only with SWITCH CP ON and ACCURACY set (docs/cell-time.md): not
    // modelled, so no path program.
    c.path_execute_command.clear();
    c.error_regex = R"(^\s*(\([A-Z]?\d+\)\s*\S.*?)\s*$)";
    c.where_joints_first = true;
    c.location_headers = {"X[mm]", "Y[mm]", "Z[mm]", "O[deg]", "A[deg]", "T[deg]"};
    return c;
  }
  std::string names;
  for (const auto& n : valPresetNames()) names += (names.empty() ? "" : ", ") + n;
  throw ConfigError("val.dialect: unknown dialect '" + dialect + "' (" + names + ")");
}

ValConfig valConfigFromJson(const json& j, const std::string& where) {
  ObjectReader r = objectReader(j, where);
  std::string dialect = "val2";
  r.get("dialect", dialect);
  ValConfig c;
  try {
    c = valPreset(dialect);
  } catch (const ConfigError&) {
    throw ConfigError(where + ".dialect: unknown dialect '" + dialect +
                      "' (val2, vplus or kawasaki-as)");
  }
  if (const json* s = r.find("serial")) c.serial = serialConfigFromJson(*s, where + ".serial");
  // One prompt as a string (older files) or the list of them.
  if (const json* p = r.find("prompt")) {
    if (p->is_string())
      c.prompt = {p->get<std::string>()};
    else if (p->is_array() &&
             std::all_of(p->begin(), p->end(), [](const json& e) { return e.is_string(); }))
      c.prompt = p->get<std::vector<std::string>>();
    else
      throw ConfigError(where +
                        ".prompt: expected a string or a list of strings, like [\".\", "
                        "\"*\"]");
  }
  r.get("send_line_ending", c.send_line_ending);
  r.get("move_joints_command", c.move_joints_command);
  r.get("where_command", c.where_command);
  r.get("speed_command", c.speed_command);
  r.get("abort_command", c.abort_command);
  r.get("path_edit_command", c.path_edit_command);
  r.get("path_move_line", c.path_move_line);
  r.get("path_end_edit", c.path_end_edit);
  r.get("path_execute_command", c.path_execute_command);
  r.get("joint_decimals", c.joint_decimals);
  r.get("error_regex", c.error_regex);
  r.get("power_off_regex", c.power_off_regex);
  r.get("out_of_range_regex", c.out_of_range_regex);
  r.get("ignore_regex", c.ignore_regex);
  r.get("question_regex", c.question_regex);
  r.get("where_joints_first", c.where_joints_first);
  r.get("location_headers", c.location_headers);
  r.get("joint_headers", c.joint_headers);
  r.get("connect_timeout_s", c.connect_timeout_s);
  r.get("command_timeout_s", c.command_timeout_s);
  r.get("where_timeout_s", c.where_timeout_s);
  r.get("move_timeout_s", c.move_timeout_s);
  r.get("slowest_joint_speed_deg_s", c.slowest_joint_speed_deg_s);
  r.get("abort_timeout_s", c.abort_timeout_s);
  r.get("poll_interval_s", c.poll_interval_s);
  r.get("at_target_tol_deg", c.at_target_tol_deg);
  r.get("still_tol_deg", c.still_tol_deg);
  r.get("still_polls", c.still_polls);
  r.get("motion_timeout_s", c.motion_timeout_s);
  r.get("stopped_short_s", c.stopped_short_s);
  r.get("where_retries", c.where_retries);
  r.finish();
  validate(c, where);
  return c;
}

void validate(const ValConfig& c, const std::string& where) {
  const auto presets = valPresetNames();
  if (std::find(presets.begin(), presets.end(), c.dialect) == presets.end())
    throw ConfigError(where + ".dialect: unknown dialect '" + c.dialect +
                      "' (val2, vplus or kawasaki-as)");
  if (c.prompt.empty()) throw ConfigError(where + ".prompt: must list at least one prompt");
  for (const auto& p : c.prompt)
    if (trim(p).empty()) throw ConfigError(where + ".prompt: a prompt must not be empty or blank");
  if (c.send_line_ending.empty())
    throw ConfigError(where + ".send_line_ending: must not be empty (\"\\r\" or \"\\r\\n\")");
  const std::set<std::string> joints{"j1", "j2", "j3", "j4", "j5", "j6"};
  const auto check_template = [&](const std::string& key, const std::string& text,
                                  const std::set<std::string>& allowed,
                                  const std::set<std::string>& required) {
    std::set<std::string> seen;
    try {
      for (const auto& f : templateFields(text)) {
        if (!allowed.count(f)) throw ConfigError(where + "." + key + ": unknown field {" + f + "}");
        seen.insert(f);
      }
    } catch (const ProtocolError& e) {
      throw ConfigError(where + "." + key + ": " + e.what());
    }
    for (const auto& f : required)
      if (!seen.count(f)) throw ConfigError(where + "." + key + ": needs the field {" + f + "}");
    if (text.empty()) throw ConfigError(where + "." + key + ": must not be empty");
  };
  check_template("move_joints_command", c.move_joints_command, joints, joints);
  check_template("where_command", c.where_command, {}, {});
  check_template("speed_command", c.speed_command, {"speed"}, {"speed"});
  check_template("abort_command", c.abort_command, {}, {});
  if (!c.path_execute_command.empty()) {  // empty: no motion through vias
    check_template("path_edit_command", c.path_edit_command, {}, {});
    check_template("path_move_line", c.path_move_line, joints, joints);
    check_template("path_end_edit", c.path_end_edit, {}, {});
    check_template("path_execute_command", c.path_execute_command, {}, {});
  }
  if (c.joint_decimals < 0 || c.joint_decimals > 6)
    throw ConfigError(where + ".joint_decimals: must be 0 to 6");
  checkRegex(c.error_regex, where + ".error_regex", 1);
  checkRegex(c.power_off_regex, where + ".power_off_regex", 0);
  checkRegex(c.out_of_range_regex, where + ".out_of_range_regex", 0);
  checkRegex(c.ignore_regex, where + ".ignore_regex", 0);
  checkRegex(c.question_regex, where + ".question_regex", 0);
  if (c.location_headers.size() != 6)
    throw ConfigError(where + ".location_headers: must name 6 columns (X Y Z O A T)");
  if (c.joint_headers.size() != 6)
    throw ConfigError(where + ".joint_headers: must name 6 columns (JT1 ... JT6)");
  checkPositive(c.connect_timeout_s, where + ".connect_timeout_s");
  checkPositive(c.command_timeout_s, where + ".command_timeout_s");
  checkPositive(c.where_timeout_s, where + ".where_timeout_s");
  checkPositive(c.move_timeout_s, where + ".move_timeout_s");
  checkPositive(c.slowest_joint_speed_deg_s, where + ".slowest_joint_speed_deg_s");
  checkPositive(c.abort_timeout_s, where + ".abort_timeout_s");
  checkPositive(c.poll_interval_s, where + ".poll_interval_s");
  checkPositive(c.at_target_tol_deg, where + ".at_target_tol_deg");
  if (c.still_tol_deg < 0) throw ConfigError(where + ".still_tol_deg: must not be negative");
  if (c.still_polls < 1) throw ConfigError(where + ".still_polls: must be at least 1");
  checkPositive(c.motion_timeout_s, where + ".motion_timeout_s");
  checkPositive(c.stopped_short_s, where + ".stopped_short_s");
  if (c.where_retries < 0 || c.where_retries > 100)
    throw ConfigError(where + ".where_retries: must be 0 to 100");
}

BarConfig barConfigFromJson(const json& j, const std::string& where) {
  BarConfig c;
  ObjectReader r = objectReader(j, where);
  if (const json* s = r.find("serial")) c.serial = serialConfigFromJson(*s, where + ".serial");
  r.get("format", c.format);
  r.get("value_regex", c.value_regex);
  r.get("unit_scale_mm", c.unit_scale_mm);
  r.get("ignore_case", c.ignore_case);
  r.get("over_range_regex", c.over_range_regex);
  r.get("no_probe_regex", c.no_probe_regex);
  r.get("error_regex", c.error_regex);
  r.get("mode", c.mode);
  r.get("poll_command", c.poll_command);
  r.get("send_line_ending", c.send_line_ending);
  r.get("poll_timeout_s", c.poll_timeout_s);
  r.get("stale_after_s", c.stale_after_s);
  r.get("range_mm", c.range_mm);
  r.finish();
  validate(c, where);
  return c;
}

void validate(const BarConfig& c, const std::string& where) {
  try {
    barPresetRegex(c.format);
  } catch (const ConfigError&) {
    throw ConfigError(where + ".format: unknown format '" + c.format +
                      "' (mm_suffix, mitutoyo or gn)");
  }
  if (!c.value_regex.empty()) checkRegex(c.value_regex, where + ".value_regex", 1);
  if (c.unit_scale_mm == 0) throw ConfigError(where + ".unit_scale_mm: must not be 0");
  checkRegex(c.over_range_regex, where + ".over_range_regex", 0);
  checkRegex(c.no_probe_regex, where + ".no_probe_regex", 0);
  checkRegex(c.error_regex, where + ".error_regex", 0);
  if (c.mode != "polled" && c.mode != "streamed")
    throw ConfigError(where + ".mode: must be polled or streamed");
  if (c.mode == "polled" && c.poll_command.empty())
    throw ConfigError(where + ".poll_command: must not be empty in polled mode");
  checkPositive(c.poll_timeout_s, where + ".poll_timeout_s");
  checkPositive(c.stale_after_s, where + ".stale_after_s");
  if (c.range_mm < 0) throw ConfigError(where + ".range_mm: must not be negative");
}

DriversConfig driversConfigFromJson(const json& j, const std::string& source) {
  DriversConfig c;
  try {
    ObjectReader r(jsonread::Reader<ConfigError>(source), j, "");
    if (const json* v = r.find("val")) c.val = valConfigFromJson(*v, "val");
    if (const json* b = r.find("bar")) c.bar = barConfigFromJson(*b, "bar");
    std::string comment;  // free text for people editing the file
    r.get("comment", comment);
    r.finish();
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    if (what.rfind(source, 0) == 0) throw;
    throw ConfigError(source + ": " + what);
  }
  return c;
}

namespace {

std::string readConfigFile(const std::string& path, const char* what) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot read the " + what);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

json parseConfigJson(const std::string& text, const std::string& source) {
  return jsonread::parseText<ConfigError>(text, source, "a drivers config (docs/drivers.md)");
}

}  // namespace

DriversConfig loadDriversConfig(const std::string& path) {
  return parseDriversConfig(readConfigFile(path, "drivers configuration file"), path);
}

DriversConfig parseDriversConfig(const std::string& text, const std::string& source) {
  return driversConfigFromJson(parseConfigJson(text, source), source);
}

DriversConfig parseDriversOrDaemonConfig(const std::string& text, const std::string& source) {
  const json j = parseConfigJson(text, source);
  // robocald.json always names its model; a drivers file has neither key.
  if (!j.is_object() || (!j.contains("model") && !j.contains("drivers")))
    return driversConfigFromJson(j, source);
  const auto drivers = j.find("drivers");
  // The daemon's source name for its section (daemon/src/config.cpp), so errors read alike.
  return drivers == j.end() ? DriversConfig{}
                            : driversConfigFromJson(*drivers, source + ": drivers");
}

DriversConfig loadDriversOrDaemonConfig(const std::string& path) {
  return parseDriversOrDaemonConfig(readConfigFile(path, "configuration file"), path);
}

json toJson(const SerialConfig& c) {
  return json{{"path", c.path},
              {"usb_serial", c.usb_serial},
              {"usb_description", c.usb_description},
              {"baud", c.baud},
              {"data_bits", c.data_bits},
              {"parity", c.parity},
              {"stop_bits", c.stop_bits},
              {"flow_control", c.flow_control},
              {"opener", c.opener},
              {"exclusive", c.exclusive}};
}

json toJson(const ValConfig& c) {
  return json{{"serial", toJson(c.serial)},
              {"dialect", c.dialect},
              {"prompt", c.prompt},
              {"send_line_ending", c.send_line_ending},
              {"move_joints_command", c.move_joints_command},
              {"where_command", c.where_command},
              {"speed_command", c.speed_command},
              {"abort_command", c.abort_command},
              {"path_edit_command", c.path_edit_command},
              {"path_move_line", c.path_move_line},
              {"path_end_edit", c.path_end_edit},
              {"path_execute_command", c.path_execute_command},
              {"joint_decimals", c.joint_decimals},
              {"error_regex", c.error_regex},
              {"power_off_regex", c.power_off_regex},
              {"out_of_range_regex", c.out_of_range_regex},
              {"ignore_regex", c.ignore_regex},
              {"question_regex", c.question_regex},
              {"where_joints_first", c.where_joints_first},
              {"location_headers", c.location_headers},
              {"joint_headers", c.joint_headers},
              {"connect_timeout_s", c.connect_timeout_s},
              {"command_timeout_s", c.command_timeout_s},
              {"where_timeout_s", c.where_timeout_s},
              {"move_timeout_s", c.move_timeout_s},
              {"slowest_joint_speed_deg_s", c.slowest_joint_speed_deg_s},
              {"abort_timeout_s", c.abort_timeout_s},
              {"poll_interval_s", c.poll_interval_s},
              {"at_target_tol_deg", c.at_target_tol_deg},
              {"still_tol_deg", c.still_tol_deg},
              {"still_polls", c.still_polls},
              {"motion_timeout_s", c.motion_timeout_s},
              {"stopped_short_s", c.stopped_short_s},
              {"where_retries", c.where_retries}};
}

json toJson(const BarConfig& c) {
  return json{{"serial", toJson(c.serial)},
              {"format", c.format},
              {"value_regex", c.value_regex},
              {"unit_scale_mm", c.unit_scale_mm},
              {"ignore_case", c.ignore_case},
              {"over_range_regex", c.over_range_regex},
              {"no_probe_regex", c.no_probe_regex},
              {"error_regex", c.error_regex},
              {"mode", c.mode},
              {"poll_command", c.poll_command},
              {"send_line_ending", c.send_line_ending},
              {"poll_timeout_s", c.poll_timeout_s},
              {"stale_after_s", c.stale_after_s},
              {"range_mm", c.range_mm}};
}

json toJson(const DriversConfig& c) {
  return json{{"val", toJson(c.val)}, {"bar", toJson(c.bar)}};
}

}  // namespace robocal::drivers
