// Crash states, not just crashes (issue 21 item 6): a short run is recorded (every durable file
// operation of robocald's data folder), then robocald is started on states a power cut may leave
// (crash_states.hpp) and the run resumed to its end. Each state must give a daemon that starts;
// every sample row that was whole on disk (and so may have been announced as a SAMPLE) is still
// there at the end; no point is measured twice and none is skipped; a torn row is cut with an
// event. The quick form (this test, the plain suite) tries a spread of states; the full form
// tries every one: scripts/crash-states.sh (ROBOCAL_CRASH_STATES=all).
#include <catch2/catch.hpp>

#include "crash_states.hpp"
#include "sim_cell.hpp"

#include <robocal/formats/samples_csv.hpp>
#include <robocal/planner/plan_json.hpp>

#include <cstdlib>
#include <filesystem>
#include <set>

using namespace robocal;
using namespace robocal::test;
using json = nlohmann::json;
namespace fs = std::filesystem;

namespace {

constexpr unsigned kSeed = 41;
// Two shells of six points each (latitudes 20, 50, 80; longitudes 0 and 180).
Cell makeCell() {
  return Cell({"B1C1", "B2C2"}, kSeed, true, 180, 100);
}

using Key = std::tuple<int, long, long>;
Key keyOf(const Sample& s) {
  return {s.shell, std::lround(s.lat_deg * 1000), std::lround(s.lon_deg * 1000)};
}

// The whole rows of a samples file (a torn last row is not one).
std::vector<Sample> wholeRows(const fs::path& file) {
  if (!fs::exists(file)) return {};
  std::string text = readTextFile(file);
  text.resize(text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1);
  if (text.empty()) return {};
  try {
    return parseSamples(text, file.string());
  } catch (const std::exception&) {
    return {};  // the header alone was torn: no rows
  }
}

}  // namespace

TEST_CASE("crash states: a power cut at any file operation of a run, restart and resume",
          "[e2e][crash][heavy]") {
  // Record a run whole.
  TempDir rec_dir;
  const std::string log = rec_dir / "file-ops.jsonl";
  ::setenv("ROBOCAL_FILE_OPS_LOG", log.c_str(), 1);
  std::string recorded_data;
  {
    Cell cell = makeCell();
    recorded_data = fs::canonical(cell.daemon->dataDir()).string();
    auto c = cell.daemon->client();
    c->send({{"cmd", "watch"}, {"enable", true}});
    REQUIRE(c->request({{"cmd", "start"}, {"token", cell.daemon->token()}}, 30, "ACK")["class"] ==
            "ACK");
    REQUIRE(cell.operate(*c, {"done", "paused", "error"}, 240) == "done");
    cell.daemon->stop();
  }
  ::unsetenv("ROBOCAL_FILE_OPS_LOG");
  std::vector<FileOp> ops;
  for (FileOp& op : loadFileOps(log))
    if (op.path.rfind(recorded_data + "/", 0) == 0) ops.push_back(std::move(op));
  REQUIRE(ops.size() > 50);
  const std::vector<CrashState> all = crashStates(ops);
  // Quick form: eight states spread over the run (torn ones among them, by the stride).
  std::vector<CrashState> tried;
  const char* which = std::getenv("ROBOCAL_CRASH_STATES");
  if (which && std::string(which) == "all") {
    tried = all;
  } else {
    for (std::size_t i = 0; i < 8; ++i) tried.push_back(all[(i * 7919 + 3) % all.size()]);
  }
  int resumed = 0, torn_repaired = 0;
  for (const CrashState& state : tried) {
    INFO(state.describe(ops));
    Cell cell = makeCell();
    REQUIRE(cell.daemon->stop() == 0);
    const std::string data = cell.daemon->dataDir();
    for (const auto& entry : fs::directory_iterator(data))
      if (entry.path().filename() != "token") fs::remove_all(entry.path());
    writeCrashState(ops, state, recorded_data, data);
    // What was whole on disk before the daemon starts again.
    std::vector<Sample> before;
    std::string run_id;
    if (fs::exists(data + "/runs"))
      for (const auto& entry : fs::directory_iterator(data + "/runs")) {
        run_id = entry.path().filename().string();
        before = wholeRows(entry.path() / "samples.csv");
      }
    cell.daemon->start();  // the daemon always starts (start() requires it to listen)
    auto c = cell.daemon->client();
    c->send({{"cmd", "watch"}, {"enable", true}});
    const json st = c->request({{"cmd", "status"}}, 10, "STATUS");
    if (st["state"] == "interrupted") {
      REQUIRE(c->request({{"cmd", "resume"}, {"token", cell.daemon->token()}}, 30,
                         "ACK")["class"] == "ACK");
      const std::string end = cell.operate(*c, {"done", "paused", "error"}, 240);
      INFO(c->request({{"cmd", "status"}}, 10, "STATUS").dump());
      REQUIRE(end == "done");
      ++resumed;
    }
    if (run_id.empty() || !fs::exists(cell.runDir(run_id) + "/state.json")) {
      CHECK(st["state"] == "idle");  // no run, or one cut short while it was created
      continue;
    }
    const std::string run = cell.runDir(run_id);
    const auto after = loadSamplesFile(run + "/samples.csv");
    std::set<Key> keys;
    for (const Sample& s : after) CHECK(keys.insert(keyOf(s)).second);  // none twice
    for (const Sample& s : before) CHECK(keys.count(keyOf(s)) == 1);    // none lost
    if (st["state"] == "interrupted") {  // resumed to its end: none skipped
      std::set<Key> planned;
      for (const auto& shell : loadPlanFile(run + "/plan.json").shells)
        for (const auto& step : shell.steps)
          if (step.kind == StepKind::kPoint)
            planned.insert(
                {shell.shell, std::lround(step.lat_deg * 1000), std::lround(step.lon_deg * 1000)});
      std::ifstream events(run + "/events.jsonl");
      for (std::string line; std::getline(events, line);) {
        const json e = json::parse(line);  // every line whole: a torn one was cut
        if (e["event"] == "point_dropped")
          planned.erase({e["shell"].get<int>(), std::lround(e["lat_deg"].get<double>() * 1000),
                         std::lround(e["lon_deg"].get<double>() * 1000)});
        torn_repaired += e["event"] == "torn_row_removed";
      }
      CHECK(keys == planned);
    }
    CHECK(cell.sim->status("broken_events") == "0");
  }
  WARN(tried.size() << " of " << all.size() << " crash states tried (" << ops.size()
                    << " file operations recorded); " << resumed << " resumed to the end, "
                    << torn_repaired << " torn lines cut");
  CHECK(resumed > 0);
}
