// robocald's whole run against robocal-cellsim speaking each controller dialect preset over real
// ptys and TCP: val2 with the busy prompt "*" while moving and synchronous moves, vplus, and
// kawasaki-as (prompt ">", JMOVE, the joint block first, completion lines). Each run reaches
// DONE with every planned point measured once and the bar never past its range.
#include <catch2/catch.hpp>

#include "sim_cell.hpp"

#include <robocal/formats/samples_csv.hpp>

using namespace robocal;
using namespace robocal::test;
using json = nlohmann::json;

namespace {

// Starts a run, answers its prompts until it is done and returns the SAMPLEs it streamed.
int runToDone(Cell& cell, proto::Client& client) {
  REQUIRE(client.request({{"cmd", "start"}, {"token", cell.daemon->token()}}, 30, "ACK")["class"] ==
          "ACK");
  std::vector<json> seen;
  const std::string end = cell.operate(client, {"done", "paused", "error", "aborted"}, 180, &seen);
  INFO(cell.daemon->logText().substr(0, 6000));
  REQUIRE(end == "done");
  int samples = 0;
  for (const json& o : seen) samples += o["class"] == "SAMPLE";
  return samples;
}

}  // namespace

TEST_CASE("a run in each controller dialect preset reaches DONE", "[e2e][dialects]") {
  struct Case {
    std::string dialect;
    std::vector<std::string> sim_args;
  };
  for (const Case& c :
       {Case{"val2", {"--val-sync-moves"}}, Case{"vplus", {}}, Case{"kawasaki-as", {}}}) {
    DYNAMIC_SECTION(c.dialect) {
      Cell cell({"B1C1", "B2C2"}, 5, true, 60, 50, json::object(), c.sim_args,
                R"({"val": {"dialect": ")" + c.dialect + R"("}})");
      auto client = cell.daemon->client();
      client->send({{"cmd", "watch"}, {"enable", true}});
      const int samples = runToDone(cell, *client);
      const json result = client->request({{"cmd", "result"}}, 10, "RESULT");
      REQUIRE(result["class"] == "RESULT");
      CHECK(static_cast<int>(loadSamplesFile(result["samples_file"].get<std::string>()).size()) ==
            samples);
      CHECK(samples >= 8);
      CHECK(cell.sim->status("broken_events") == "0");
      CHECK(cell.sim->status("moving") == "0");
    }
  }
}

TEST_CASE("a Staubli RX160 under V+ runs to DONE with every connection check passed",
          "[e2e][dialects][robots]") {
  // Another arm than the PUMA end to end: its nominal model (numeric inverse kinematics in the
  // planner and re-plans), cellsim playing it under V+, typical realism (backlash). The connect
  // pose is the shell's top, where on this arm the check's pre-point moves the bar more than the
  // check's step: the joints are stepped back a group at a time (approachStages) and the check
  // passes a seated bar (it failed shell 1 of the main job before).
  Cell cell({"B1C1", "B3C1"}, 5, true, 60, 50, json::object(), {"--realism", "typical"},
            R"({"val": {"dialect": "vplus"}})", ROBOCAL_SOURCE_DIR "/config/rx160.json");
  auto client = cell.daemon->client();
  client->send({{"cmd", "watch"}, {"enable", true}});
  REQUIRE(client->request({{"cmd", "start"}, {"token", cell.daemon->token()}}, 30,
                          "ACK")["class"] == "ACK");
  const std::string end = cell.operate(*client, {"done", "paused", "error", "aborted"}, 240);
  const json st = client->request({{"cmd", "status"}}, 10, "STATUS");
  INFO(cell.daemon->logText().substr(0, 6000));
  REQUIRE(end == "done");
  const auto run_dir = cell.runDir(st["run"]);
  CHECK(countEvents(run_dir, "connection_check") == 2);
  CHECK(countEvents(run_dir, "check_pre_point_skipped") == 0);
  CHECK(cell.sim->status("broken_events") == "0");
  const json result = client->request({{"cmd", "result"}}, 10, "RESULT");
  REQUIRE(result["class"] == "RESULT");
  CHECK(loadSamplesFile(result["samples_file"].get<std::string>()).size() >= 8);
}

TEST_CASE("a plan through vias runs each point's vias as one path program, twice",
          "[e2e][dialects][paths]") {
  // motion.through_vias in the plan's cell: the daemon sends the moves from one point to the next
  // as a path program (EDIT ... EXECUTE), cellsim blends its corners as much as the cell says
  // (blend_deg), the plan stops at a via where the blended corner would leave the bar's
  // tolerance, and the bar is watched along the path as along a move. A second run after the
  // first, from its end.
  Cell cell({"B1C1", "B2C2"}, 5, true, 60, 50, json::object(), {"--blend-deg", "3"}, "", kModel,
            {{"motion", {{"through_vias", true}, {"blend_deg", 3}}}});
  auto client = cell.daemon->client();
  client->send({{"cmd", "watch"}, {"enable", true}});
  long paths_before = 0;
  for (int run = 1; run <= 2; ++run) {
    INFO("run " << run);
    CHECK(runToDone(cell, *client) >= 8);
    const long paths = std::stol(cell.sim->status("paths"));
    CHECK(paths > paths_before);  // points reached through vias, each by one program
    paths_before = paths;
    CHECK(cell.sim->status("broken_events") == "0");
    CHECK(cell.sim->status("moving") == "0");
    UNSCOPED_INFO("cellsim after run " << run << ": moves " << cell.sim->status("moves")
                                       << ", paths " << paths << ", peak deflection moving "
                                       << cell.sim->status("moving_peak_mm") << " mm");
  }
  CHECK(std::stod(cell.sim->status("moving_peak_mm")) < 1.6);  // the daemon's hard limit
}
