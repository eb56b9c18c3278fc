// The ISO 9283-style test end to end (docs/iso9283.md): planned with robocal iso-plan, run by
// robocald on cellsim with a realistic arm (backlash, compliance, warm-up, the LVDT's errors), so
// that repeatability and drift are not zero, and reported at the run's end instead of a fit.
#include <catch2/catch.hpp>

#include "../cli/cli_helpers.hpp"
#include "../drivers/cellsim_process.hpp"
#include "daemon_process.hpp"
#include "sim_cell.hpp"

#include <robocal/formats/error.hpp>

#include <filesystem>
#include <sstream>
#include <string>

using namespace robocal;
using namespace robocal::test;
using json = nlohmann::json;

TEST_CASE("an ISO 9283-style test runs in cellsim and reports its figures with 95 % intervals",
          "[e2e][iso]") {
  // The adaptive dwell configured: an ISO test's poses still get the full dwell (below).
  const json adaptive = {
      {"dwell_mode", "adaptive"}, {"adaptive_window_s", 0.01}, {"bar_noise_mm", 0.05}};
  Cell cell({"B1C1"}, 31, true, 60, 50, adaptive, {"--realism", "typical"});
  const std::string plan = cell.dir / "iso.json";
  const auto planned =
      runRobocal("iso-plan --model " + kModel + " --cell " + (cell.dir / "cell.json") +
                 " --cycles 6 --warmup-cycles 1 --out " + plan);
  INFO(planned.output);
  REQUIRE(planned.exit_code == 0);
  auto c = cell.daemon->client();
  c->send({{"cmd", "watch"}, {"enable", true}});
  REQUIRE(c->request({{"cmd", "start"}, {"token", cell.daemon->token()}, {"plan", plan}}, 30,
                     "ACK")["class"] == "ACK");
  std::vector<json> seen;
  REQUIRE(cell.operate(*c, {"done", "paused", "error", "aborted"}, 300, &seen) == "done");
  const json st = c->request({{"cmd", "status"}}, 10, "STATUS");
  const std::string run = cell.runDir(st["run"]);

  // The clients were told, with the figures; nothing was fitted.
  bool told = false;
  for (const json& o : seen) told |= o["class"] == "EVENT" && o.value("event", "") == "iso_report";
  CHECK(told);
  CHECK_FALSE(std::filesystem::exists(run + "/result-set1.json"));
  const json report = json::parse(readTextFile(run + "/iso9283.json"));
  CHECK(report["class"] == "ISO9283");
  CHECK(report["connection"] == "B1C1");
  CHECK(report["warmup_cycles"] == 1);
  REQUIRE(report["poses"].size() == 5);
  for (const json& p : report["poses"]) {
    CHECK(p["cycles"] == 6);
    const json& rd = p["distance_repeatability_mm"];
    const json& ad = p["distance_accuracy_mm"];
    // A real arm and a real bar: repeatability is not zero, and each interval holds its figure.
    CHECK(rd["value"].get<double>() > 0.005);
    CHECK(rd["low95"].get<double>() < rd["value"].get<double>());
    CHECK(rd["value"].get<double>() < rd["high95"].get<double>());
    CHECK(ad["low95"].get<double>() < ad["value"].get<double>());
    CHECK(ad["value"].get<double>() < ad["high95"].get<double>());
  }
  CHECK(report["pairs"].size() == 4);
  REQUIRE(report["drift_mm"].is_object());
  CHECK(report["drift_mm"]["span_min"].get<double>() > 0);
  CHECK(report["drift_mm"]["value"].get<double>() != 0);
  CHECK(report["limits"].size() >= 3);
  CHECK(readTextFile(run + "/iso9283.txt").find("What a ball-bar cannot give") !=
        std::string::npos);

  // Every pose was read after the full dwell, as the standard's "settled".
  int timed = 0;
  std::istringstream events(readTextFile(run + "/events.jsonl"));
  for (std::string line; std::getline(events, line);) {
    const json e = json::parse(line);
    if (e["event"] != "timing") continue;
    ++timed;
    CHECK(e["dwell_mode"] == "fixed");
  }
  CHECK(timed > 0);

  // Offline, the same samples and plan give the same figures.
  const auto offline = runRobocal("iso-report --model " + kModel + " " + run + "/samples.csv" +
                                  " --plan " + plan + " --json");
  REQUIRE(offline.exit_code == 0);
  json a = json::parse(offline.output), b = report;
  a.erase("conditions");
  b.erase("conditions");
  CHECK(a == b);
}
