// robocal run-timing on an event log written here: the timing quantiles, how the points dwelt
// (adaptive or fixed, the audits, the adaptive dwell turned off, the noise measured), and what a
// damaged log or one without timing events gives.
#include <catch2/catch.hpp>

#include "cli_helpers.hpp"

#include <fstream>
#include <nlohmann/json.hpp>

using namespace robocal::test;
using json = nlohmann::json;

namespace {

json timing(const std::string& mode, bool steady, double achieved_ms) {
  return {{"event", "timing"},
          {"shell", 1},
          {"settle_s", 2.0},
          {"dwell_mode", mode},
          {"steady", steady},
          {"settle_achieved_ms", achieved_ms},
          {"settle_error_ms", achieved_ms - 2000},
          {"where_ms", 5.0},
          {"motion_to_disk_ms", achieved_ms + 300}};
}

}  // namespace

TEST_CASE("robocal run-timing: quantiles and how the points dwelt, also the audits",
          "[cli][settling]") {
  TempDir dir;
  {
    std::ofstream out(dir.path / "events.jsonl");
    out << json{{"event", "connection_check"}, {"ok", true}, {"still_noise_mm", 0.00104}} << "\n";
    out << json{{"event", "dwell_audit"}, {"passed", true}} << "\n";
    out << timing("adaptive", false, 2000).dump() << "\n";
    out << timing("adaptive", true, 600).dump() << "\n";
    out << timing("adaptive", true, 700).dump() << "\n";
    out << "{not json\n";
    out << json{{"event", "dwell_audit"}, {"passed", false}} << "\n";
    out << json{{"event", "dwell_audit"}, {"passed", false}} << "\n";
    out << json{{"event", "adaptive_dwell_off"}, {"reason", "differed again"}} << "\n";
    out << timing("fixed", false, 2001).dump() << "\n";
    out << json{{"event", "timing"}, {"steady", "yes"}} << "\n";  // damaged: skipped, named
  }
  const auto r = runRobocal("run-timing " + dir.path.string() + " --json", false);
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  const json out = json::parse(r.output);
  CHECK(out["points"] == 4);
  const json& d = out["dwell"];
  CHECK(d["adaptive"] == 3);
  CHECK(d["fixed"] == 1);
  CHECK(d["ended_early"] == 2);
  CHECK(d["audits"] == 3);
  CHECK(d["audits_failed"] == 2);
  CHECK(d["turned_off"] == json::array({"differed again"}));
  CHECK(d["still_noise_mm"] == json::array({0.00104}));
  CHECK(out["settle_achieved_ms"]["min"] == 600.0);
  CHECK(out["settle_achieved_ms"]["max"] == 2001.0);
  const auto text = runRobocal("run-timing " + dir.path.string());
  INFO(text.output);
  REQUIRE(text.exit_code == 0);
  // What was skipped is named by file and line.
  CHECK_THAT(text.output, Catch::Contains("events.jsonl:6: not JSON, skipped"));
  CHECK_THAT(text.output, Catch::Contains("events.jsonl:11:"));
  CHECK_THAT(text.output, Catch::Contains("dwell: 3 adaptive (2 ended early by steady readings), "
                                          "1 fixed; 3 audits, 2 failed"));
  CHECK_THAT(text.output, Catch::Contains("the adaptive dwell was turned off: differed again"));
  CHECK_THAT(text.output, Catch::Contains("0.00104"));
}

TEST_CASE("robocal run-timing: a run without timing events, or without a log, is an error",
          "[cli][settling]") {
  TempDir dir;
  std::ofstream(dir.path / "events.jsonl") << json{{"event", "prompt"}} << "\n";
  const auto none = runRobocal("run-timing " + dir.path.string());
  CHECK(none.exit_code == 1);
  CHECK_THAT(none.output, Catch::Contains("no timing events"));
  const auto missing = runRobocal("run-timing " + (dir.path / "nowhere").string());
  CHECK(missing.exit_code == 1);
  CHECK_THAT(missing.output, Catch::Contains("nowhere/events.jsonl"));
}
