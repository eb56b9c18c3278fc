// The run store on its own: what it writes must survive any text a device sends.
#include <catch2/catch.hpp>

#include "../cli/cli_helpers.hpp"

#include <robocal/daemon/run_store.hpp>

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
