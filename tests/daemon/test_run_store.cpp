// The run store on its own: what it writes must survive any text a device sends.
#include <catch2/catch.hpp>

#include "../cli/cli_helpers.hpp"

#include <robocal/daemon/run_store.hpp>
#include <robocal/formats/samples_csv.hpp>

#include <algorithm>
#include <fstream>

using namespace robocal;
using namespace robocal::test;

TEST_CASE("a pause reason quoting a garbled reply (not UTF-8) is recorded in state and log") {
  TempDir dir;
  daemon::RunStore store(dir.path.string());
  daemon::RunDir run = store.create("{}\n");
  const std::string reason = "unreadable WHERE reply '12.5\x93\xF1\xFE 3.0'";
  REQUIRE_NOTHROW(run.setState({{"status", "paused"}, {"reason", reason}}));
  REQUIRE_NOTHROW(run.logEvent({{"event", "paused"}, {"reason", reason}}));
  CHECK(run.state()["status"] == "paused");
  std::ifstream events(run.file("events.jsonl"));
  std::string line;
  REQUIRE(std::getline(events, line));
  CHECK(nlohmann::json::parse(line)["event"] == "paused");
}

TEST_CASE("the newest fit on disk is found again, and damaged result files are skipped and named") {
  TempDir dir;
  daemon::RunStore store(dir.path.string());
  CHECK_FALSE(store.latestResult().has_value());
  auto result = [](const std::string& run, int set) {
    return nlohmann::json{{"class", "RESULT"},
                          {"run", run},
                          {"set", set},
                          {"calibrated_file", "calibrated-set" + std::to_string(set) + ".json"},
                          {"rms_mm", 0.01}};
  };
  daemon::RunDir older = store.create("{}\n");
  older.writeJson("result-set1.json", result(older.id(), 1));
  older.writeJson("result-set2.json", result(older.id(), 2));
  REQUIRE(store.latestResult().has_value());
  CHECK((*store.latestResult())["set"] == 2);

  daemon::RunDir newer = store.create("{}\n");
  REQUIRE(newer.id() > older.id());
  newer.writeJson("result-set1.json", result(newer.id(), 1));
  {
    std::ofstream torn(newer.file("result-set2.json"));
    torn << "{\"class\": \"RESULT\", \"set\": 2, \"rms";  // cut off mid-write
  }
  // Valid JSON, but not what the daemon could serve: no run named.
  newer.writeJson("result-set3.json", {{"class", "RESULT"}, {"set", 3}, {"run", nullptr}});
  std::vector<std::string> skipped;
  const auto latest = store.latestResult(&skipped);
  REQUIRE(latest.has_value());
  CHECK((*latest)["run"] == newer.id());
  CHECK((*latest)["set"] == 1);
  REQUIRE(skipped.size() == 2);
  std::sort(skipped.begin(), skipped.end());
  CHECK(skipped[0].find("result-set2.json") != std::string::npos);
  CHECK(skipped[1].find("result-set3.json") != std::string::npos);
}

TEST_CASE(
    "samples carry their time, and a run folder from before the time column keeps its layout") {
  TempDir dir;
  daemon::RunStore store(dir.path.string());
  Sample s;
  s.shell = 1;
  s.length_mm = 150.1;
  s.time_s = 1764921600.5;
  daemon::RunDir fresh = store.create("{}\n");
  fresh.appendSample(s, 0.002);
  fresh.appendSample(s, 0.003);
  std::vector<Sample> back = fresh.loadSamples();
  REQUIRE(back.size() == 2);
  REQUIRE(back[1].time_s);
  CHECK(*back[1].time_s == Approx(1764921600.5).margin(1e-3));
  // How the point was reached travels with it (robocal solve reads it back).
  s.approach_deg = 0.02;
  fresh.appendSample(s, 0.004);
  back = fresh.loadSamples();
  REQUIRE(back.size() == 3);
  CHECK_FALSE(back[0].approach_deg);  // not said: an empty field
  REQUIRE(back[2].approach_deg);
  CHECK(*back[2].approach_deg == Approx(0.02));

  // A folder an older robocald wrote (no time_s in its header), resumed by this one: the new rows
  // have the header's fields, so the file still loads, without times.
  daemon::RunDir old = store.create("{}\n");
  std::ofstream(old.file("samples.csv"))
      << kSamplesHeader << ",bar_spread_mm\n"
      << "1,1,1,0.000,10.0000,0.0000,1,2,3,4,5,6,150.000000,0.0010\n";
  daemon::RunDir reopened(old.path());
  reopened.appendSample(s, 0.002);
  back = reopened.loadSamples();
  REQUIRE(back.size() == 2);
  CHECK_FALSE(back[1].time_s);
  CHECK_FALSE(back[1].approach_deg);
  CHECK(back[1].length_mm == Approx(150.1));
}
