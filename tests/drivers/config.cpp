// The drivers configuration: defaults, JSON parsing, errors that name the key.
#include <robocal/drivers/config.hpp>
#include <robocal/drivers/errors.hpp>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <fstream>

using namespace robocal::drivers;
using nlohmann::json;

namespace {
std::string errorOf(const std::string& text) {
  try {
    driversConfigFromJson(json::parse(text), "cell.json");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("Config: defaults are hardware.md's and survive a JSON round trip", "[drivers][config]") {
  const DriversConfig d;
  CHECK(d.val.prompt == std::vector<std::string>{".", "*"});
  CHECK(d.val.dialect == "val2");
  CHECK(d.val.serial.baud == 9600);
  CHECK(d.val.where_command == "WHERE");
  CHECK(d.bar.mode == "polled");
  const DriversConfig back = driversConfigFromJson(toJson(d), "round trip");
  CHECK(toJson(back) == toJson(d));
  CHECK_NOTHROW(driversConfigFromJson(json::object(), "empty"));
}

TEST_CASE("Config: the shipped example parses", "[drivers][config]") {
  const DriversConfig c = loadDriversConfig(ROBOCAL_SOURCE_DIR "/config/drivers.json");
  CHECK(c.val.serial.baud == 9600);
  CHECK(c.val.dialect == "val2");
  CHECK(c.bar.format == "mm_suffix");  // the preset's value pattern, not one pinned in the file
  CHECK(c.bar.value_regex.empty());
}

TEST_CASE("Config: switching the dialect alone in the shipped file gives that preset",
          "[drivers][config]") {
  // The shipped file names the ports and the dialect and nothing a preset sets: a user who
  // changes "dialect" gets the whole preset (a file that pinned VAL II's prompts kept them).
  std::ifstream in(ROBOCAL_SOURCE_DIR "/config/drivers.json");
  const json shipped = json::parse(in);
  for (const std::string& dialect : valPresetNames()) {
    INFO(dialect);
    json edited = shipped;
    edited["val"]["dialect"] = dialect;
    const DriversConfig c = driversConfigFromJson(edited, "drivers.json");
    ValConfig expected = valPreset(dialect);
    expected.serial = c.val.serial;
    CHECK(toJson(DriversConfig{expected, c.bar})["val"] == toJson(c)["val"]);
  }
}

TEST_CASE("Config: errors name the key", "[drivers][config]") {
  CHECK_THAT(errorOf(R"({"val": {"serial": {"baud": "fast"}}})"),
             Catch::Contains("cell.json: val.serial.baud: expected a whole number"));
  CHECK_THAT(errorOf(R"({"val": {"promt": ">"}})"), Catch::Contains("val.promt: unknown key"));
  CHECK_THAT(errorOf(R"({"bar": {"value_regex": "([0-9]"}})"),
             Catch::Contains("bar.value_regex: not a valid regular expression"));
  CHECK_THAT(errorOf(R"({"bar": {"value_regex": "[0-9]+"}})"),
             Catch::Contains("bar.value_regex: the regular expression needs 1 capture"));
  CHECK_THAT(errorOf(R"({"val": {"move_joints_command": "MOVE {j1} {j2}"}})"),
             Catch::Contains("val.move_joints_command: needs the field {j3}"));
  CHECK_THAT(errorOf(R"({"val": {"speed_command": "SPEED {sped}"}})"),
             Catch::Contains("val.speed_command: unknown field {sped}"));
  CHECK_THAT(errorOf(R"({"bar": {"mode": "pushed"}})"), Catch::Contains("bar.mode"));
  CHECK_THAT(errorOf(R"({"bar": {"format": "csv"}})"), Catch::Contains("bar.format"));
  CHECK_THAT(errorOf(R"({"val": {"joint_headers": ["JT1"]}})"),
             Catch::Contains("val.joint_headers"));
  CHECK_THAT(errorOf(R"({"val": {"where_timeout_s": 0}})"), Catch::Contains("val.where_timeout_s"));
  CHECK_THAT(errorOf(R"({"val": {"serial": {"parity": "sometimes"}}})"),
             Catch::Contains("val.serial.parity"));
  CHECK_THAT(errorOf(R"([1, 2])"), Catch::Contains("cell.json"));
}

TEST_CASE("Config: a number too large for a double is a ConfigError (found by fuzz_drivers_config)",
          "[drivers][config]") {
  // nlohmann::json reports it as out_of_range, not parse_error: it used to escape as that.
  try {
    parseDriversConfig(R"({"val": {"serial": {"baud": 9601e308}}})", "drivers.json");
    FAIL("no error");
  } catch (const ConfigError& e) {
    CHECK_THAT(e.what(), Catch::Contains("drivers.json: not valid JSON"));
  }
}

TEST_CASE("Config: probe's reader takes robocald's config file, reading its drivers section",
          "[drivers][config][probe]") {
  // The shipped daemon config: its drivers section, as the daemon reads it.
  const DriversConfig shipped =
      loadDriversOrDaemonConfig(ROBOCAL_SOURCE_DIR "/config/robocald.json");
  CHECK(shipped.bar.mode == "streamed");
  CHECK(shipped.bar.serial.usb_description == "Prolific");
  CHECK_THAT(shipped.val.serial.path, Catch::Contains("/dev/serial/by-id/"));
  // A drivers file reads as before.
  const DriversConfig drivers =
      loadDriversOrDaemonConfig(ROBOCAL_SOURCE_DIR "/config/drivers.json");
  CHECK(toJson(drivers) == toJson(loadDriversConfig(ROBOCAL_SOURCE_DIR "/config/drivers.json")));
  // A daemon config without a drivers section: the defaults.
  CHECK(toJson(parseDriversOrDaemonConfig(R"({"model": "m.json", "bar_hard_limit_mm": 1.8})",
                                          "robocald.json")) == toJson(DriversConfig{}));
  // Errors name the file and the section as the daemon's do; the daemon's other keys are not
  // checked here, and a drivers file still refuses them.
  auto errorOfText = [](const std::string& text) -> std::string {
    try {
      parseDriversOrDaemonConfig(text, "robocald.json");
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  };
  CHECK_THAT(errorOfText(R"({"model": "m.json", "drivers": {"val": {"serial": {"baud": "x"}}}})"),
             Catch::Contains("robocald.json: drivers: val.serial.baud: expected a whole number"));
  CHECK(errorOfText(R"({"model": "m.json", "settle_s": "whatever"})").empty());
  CHECK_THAT(errorOfText(R"({"val": {}, "bar_hard_limit_mm": 1.8})"),
             Catch::Contains("bar_hard_limit_mm: unknown key"));
  CHECK_THAT(errorOfText("{"), Catch::Contains("robocald.json: not valid JSON"));
  try {
    loadDriversOrDaemonConfig("/nonexistent/robocald.json");
    FAIL("no error");
  } catch (const ConfigError& e) {
    CHECK_THAT(e.what(), Catch::Contains("/nonexistent/robocald.json: cannot read"));
  }
}
