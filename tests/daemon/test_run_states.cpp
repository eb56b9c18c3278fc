// The run controller's state machine, in-process against a scripted cell (scripted_cell.hpp):
// prompts, pauses, aborts, resumes, nudges, set numbering, re-centring and faults, each in a few
// seconds. The daemon's pty/TCP tests (test_daemon_*.cpp) remain the acceptance for the whole.
#include <catch2/catch.hpp>

#include "../cli/cli_helpers.hpp"
#include "daemon_process.hpp"
#include "scripted_cell.hpp"

#include <robocal/daemon/run.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/planner/cell_json.hpp>

#include <cmath>
#include <condition_variable>
#include <fstream>
#include <functional>
#include <mutex>
#include <optional>
#include <set>

using namespace robocal;
using namespace robocal::test;
using json = nlohmann::json;

namespace {

class Harness {
 public:
  // What the operator does at a prompt: true confirms it (attaching or detaching the bar first).
  std::function<bool(const json& prompt)> at_prompt = [](const json&) { return true; };

  Harness(const std::vector<std::string>& connections, const std::vector<double>& extensions_mm,
          double truth_error_mm = 0, std::function<void(daemon::DaemonConfig&)> configure = {})
      : configure_(std::move(configure)),
        nominal_(loadModelFile(ROBOCAL_SOURCE_DIR "/config/puma560-paper.json")),
        cell_(cellFromJson(smallCell(connections, extensions_mm, 90))),
        plan_(planCell(nominal_, cell_)) {
    ParamVector p = toParams(nominal_);
    p[linkParamIndex(2)] += truth_error_mm;  // a link longer than the model says
    auto scripted =
        std::make_unique<ScriptedCell>(withParams(nominal_, p), cell_.bar.nominal_length_mm,
                                       plan_.shells.front().connect.joints_deg);
    cell_io_ = scripted.get();
    start(std::move(scripted));
  }
  ~Harness() { run_.reset(); }

  // A new controller on the same data folder and cell, as after a daemon restart.
  void restart() {
    auto scripted = cell_io_->restarted();
    run_.reset();
    cell_io_ = scripted.get();
    start(std::move(scripted));
  }

  daemon::RunController& run() { return *run_; }
  std::string runDir(const std::string& id) const { return dir_.path.string() + "/runs/" + id; }
  ScriptedCell& cell() { return *cell_io_; }
  const Plan& plan() const { return plan_; }
  int points() const {
    int n = 0;
    for (const auto& s : plan_.shells)
      for (const auto& st : s.steps) n += st.kind == StepKind::kPoint;
    return n;
  }

  // Waits for a STATE to one of `states`; its "to", or "" after the timeout.
  std::string waitState(const std::set<std::string>& states, double timeout_s = 60) {
    std::unique_lock lock(mutex_);
    std::string to;
    changed_.wait_for(lock, std::chrono::duration<double>(timeout_s), [&] {
      for (std::size_t i = state_seen_; i < seen_.size(); ++i)
        if (seen_[i].value("class", "") == "STATE" && states.count(seen_[i].value("to", ""))) {
          to = seen_[i]["to"];
          state_seen_ = i + 1;
          return true;
        }
      return false;
    });
    return to;
  }
  std::vector<json> seen(const std::string& cls) const {
    std::lock_guard lock(mutex_);
    std::vector<json> out;
    for (const json& o : seen_)
      if (o.value("class", "") == cls) out.push_back(o);
    return out;
  }
  // Checks made on the run thread (in at_prompt or a publish): Catch2's assertions are for the
  // test's own thread only, so they are collected here and checked by the test with problems().
  void expect(bool ok, const std::string& what) {
    if (ok) return;
    std::lock_guard lock(mutex_);
    problems_.push_back(what);
  }
  std::vector<std::string> problems() const {
    std::lock_guard lock(mutex_);
    return problems_;
  }

  std::vector<json> events(const std::string& name) const {
    std::vector<json> out;
    for (const json& e : seen("EVENT"))
      if (e.value("event", "") == name) out.push_back(e);
    return out;
  }

 private:
  void start(std::unique_ptr<ScriptedCell> io) {
    daemon::DaemonConfig config;
    config.data_dir = dir_.path.string();
    config.settle_s = 0;
    config.bar_window_s = 0.02;
    config.connection_check_mm = 0;  // its half-second windows are tested on their own
    config.drivers.bar.stale_after_s = 0.1;
    if (configure_) configure_(config);
    run_ = std::make_unique<daemon::RunController>(
        config, nominal_, cell_, [this](json o, bool droppable) { published(o, droppable); },
        std::move(io));
  }

  void published(const json& o, bool droppable) {
    if (droppable) return;  // BAR lines
    if (o.value("class", "") == "PROMPT" && at_prompt(o)) {
      if (o["action"] == "connect")
        cell_io_->attach(o["ball"], o["chuck"], o["extension_mm"]);
      else
        cell_io_->detach();
      const std::string refused = run_->confirm(o["shell"].get<int>());
      expect(refused.empty(), "confirm refused: " + refused);
    }
    std::lock_guard lock(mutex_);
    seen_.push_back(o);
    changed_.notify_all();
  }

  std::function<void(daemon::DaemonConfig&)> configure_;
  TempDir dir_;
  Model nominal_;
  CellConfig cell_;
  Plan plan_;
  ScriptedCell* cell_io_ = nullptr;
  std::unique_ptr<daemon::RunController> run_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<json> seen_;
  std::vector<std::string> problems_;
  std::size_t state_seen_ = 0;
};

std::set<std::tuple<int, double, double>> pointsOf(const std::vector<json>& samples) {
  std::set<std::tuple<int, double, double>> out;
  for (const json& s : samples)
    out.insert({s["shell"].get<int>(), s["lat_deg"].get<double>(), s["lon_deg"].get<double>()});
  return out;
}

}  // namespace

TEST_CASE("run states: a whole run, the bar detached at the end, then a second run",
          "[daemon][states]") {
  Harness h({"B1C1", "B2C2"}, {0});
  REQUIRE(h.run().start(h.plan()).empty());
  CHECK_FALSE(h.run().start(h.plan()).empty());  // one run at a time
  REQUIRE(h.waitState({"done", "paused", "error", "aborted"}) == "done");
  CHECK(h.seen("SAMPLE").size() == static_cast<std::size_t>(h.points()));
  CHECK(pointsOf(h.seen("SAMPLE")).size() == static_cast<std::size_t>(h.points()));
  const auto prompts = h.seen("PROMPT");
  REQUIRE(prompts.size() == 4);  // connect 1, detach, connect 2, detach at the end
  CHECK(prompts[0]["action"] == "connect");
  CHECK(prompts[1]["action"] == "detach");
  CHECK(prompts[2]["action"] == "connect");
  CHECK(prompts[3]["action"] == "detach");
  CHECK(prompts[3]["shell"] == 0);
  CHECK_FALSE(h.cell().attached());
  CHECK_FALSE(h.run().status().bar_attached);
  REQUIRE(h.seen("RESULT").size() == 1);
  CHECK(h.seen("RESULT")[0]["set"] == 1);
  CHECK(h.run().runs()["runs"].size() == 1);
  CHECK(h.run().runs()["runs"][0]["status"] == "done");

  // The second run starts with a connect: the bar was confirmed off at the end of the first.
  REQUIRE(h.run().start(h.plan()).empty());
  REQUIRE(h.waitState({"done", "paused", "error", "aborted"}) == "done");
  const auto again = h.seen("PROMPT");
  REQUIRE(again.size() == 8);
  CHECK(again[4]["action"] == "connect");
  CHECK(h.run().runs()["runs"].size() == 2);
  CHECK(h.problems().empty());
}

TEST_CASE("run states: each run audits its first steady dwell, a second run too",
          "[daemon][states][settling]") {
  // The adaptive dwell on the scripted (noiseless) bar, its noise configured: every dwell is
  // steady. One audit a run's worth of points: the audits' count starts afresh with each run,
  // so each run's first point is audited (counted on from the first run, the second run's
  // would not be).
  int points = 0;
  const auto adaptive = [&points](daemon::DaemonConfig& c) {
    c.settle_s = 0.3;
    c.dwell_mode = "adaptive";
    c.adaptive_window_s = 0.05;
    c.bar_noise_mm = 0.01;
    c.adaptive_audit_every = points + 1;
  };
  {
    Harness probe({"B1C1"}, {0});
    points = probe.points();
  }
  REQUIRE(points >= 2);
  Harness h({"B1C1"}, {0}, 0, adaptive);
  for (int run = 1; run <= 2; ++run) {
    INFO("run " << run);
    REQUIRE(h.run().start(h.plan()).empty());
    REQUIRE(h.waitState({"done", "paused", "error", "aborted"}) == "done");
    const auto audits = h.events("dwell_audit");
    const auto samples = h.seen("SAMPLE");
    REQUIRE(samples.size() == static_cast<std::size_t>(run * points));
    REQUIRE(audits.size() == static_cast<std::size_t>(run));
    const json& first = samples[static_cast<std::size_t>((run - 1) * points)];
    CHECK(audits.back()["lat_deg"] == first["lat_deg"]);
    CHECK(audits.back()["lon_deg"] == first["lon_deg"]);
    CHECK(audits.back()["passed"] == true);  // a noiseless bar at rest reads the same
    CHECK(audits.back()["difference_mm"].get<double>() == Approx(0).margin(1e-9));
  }
  CHECK(h.events("adaptive_dwell_off").empty());
  // The steady dwells not audited ended well before settle_s: the SAMPLEs say how long.
  int short_dwells = 0;
  for (const json& s : h.seen("SAMPLE")) short_dwells += s["dwell_s"].get<double>() < 0.2;
  CHECK(short_dwells >= 2 * points - 2 - 2);  // all but the two audited, bar a late thread or two
  CHECK(h.problems().empty());
}

TEST_CASE("run states: with adaptive_audit_every 0 no dwell is audited",
          "[daemon][states][settling]") {
  Harness h({"B1C1"}, {0}, 0, [](daemon::DaemonConfig& c) {
    c.settle_s = 0.3;
    c.dwell_mode = "adaptive";
    c.adaptive_window_s = 0.05;
    c.bar_noise_mm = 0.01;
    c.adaptive_audit_every = 0;
  });
  REQUIRE(h.run().start(h.plan()).empty());
  REQUIRE(h.waitState({"done", "paused", "error", "aborted"}) == "done");
  CHECK(h.seen("SAMPLE").size() == static_cast<std::size_t>(h.points()));
  CHECK(h.events("dwell_audit").empty());
  CHECK(h.problems().empty());
}

TEST_CASE("run states: readings queued while the arm moved stay out of the point's window",
          "[daemon][states]") {
  // settle_s is 0 here: the run thread reaches each window with no dwell in which to read what
  // queued up while the arm moved, as a thread that is late on a loaded machine does.
  Harness h({"B1C1", "B2C2"}, {0});
  h.cell().queueReadingsInMotion();
  REQUIRE(h.run().start(h.plan()).empty());
  REQUIRE(h.waitState({"done", "paused", "error", "aborted"}) == "done");
  const auto samples = h.seen("SAMPLE");
  REQUIRE(samples.size() == static_cast<std::size_t>(h.points()));
  // The scripted bar has no noise: at rest every reading of a window is the same.
  for (const json& s : samples) {
    INFO(s.dump());
    CHECK(s["spread_mm"].get<double>() < 1e-9);
  }
}

TEST_CASE("run states: a pause at a prompt, a resume, a pause again and a second resume",
          "[daemon][states]") {
  Harness h({"B1C1", "B2C2"}, {0});
  int connects = 0;
  h.at_prompt = [&](const json& p) {
    if (p["action"] == "connect" && ++connects <= 2) {
      h.expect(h.run().pause("coffee").empty(), "pause at the prompt refused");
      return false;
    }
    return true;
  };
  REQUIRE(h.run().start(h.plan()).empty());
  REQUIRE(h.waitState({"paused", "done", "error"}) == "paused");
  CHECK(h.seen("SAMPLE").empty());
  CHECK_FALSE(h.run().status().resumable.empty());
  CHECK_FALSE(h.run().start(h.plan()).empty());  // resume or abort it first
  // A pause of a paused run says it is paused, not that there is no run.
  CHECK_THAT(h.run().pause({}),
             Catch::Contains("already paused") && Catch::Contains("resume continues it"));
  REQUIRE(h.run().resume("").empty());
  REQUIRE(h.waitState({"paused", "done", "error"}) == "paused");  // paused at its prompt again
  REQUIRE(h.run().resume("").empty());
  REQUIRE(h.waitState({"paused", "done", "error"}) == "done");
  CHECK(h.seen("SAMPLE").size() == static_cast<std::size_t>(h.points()));
  CHECK(h.run().runs()["runs"][0]["status"] == "done");
  CHECK(h.problems().empty());
}

TEST_CASE("run states: aborting a paused run tells the watchers, and it cannot be resumed",
          "[daemon][states]") {
  Harness h({"B1C1"}, {0});
  h.at_prompt = [&](const json&) {
    h.expect(h.run().pause({}).empty(), "pause at the prompt refused");
    return false;
  };
  REQUIRE(h.run().start(h.plan()).empty());
  REQUIRE(h.waitState({"paused", "done", "error"}) == "paused");
  const auto answer = h.run().abort("wrong fixture");
  CHECK(answer.error.empty());
  REQUIRE(h.waitState({"aborted"}, 10) == "aborted");
  const json last_state = h.seen("STATE").back();
  CHECK(last_state["from"] == "paused");
  CHECK_THAT(last_state["reason"].get<std::string>(), Catch::Contains("wrong fixture"));
  CHECK(h.run().runs()["runs"][0]["status"] == "aborted");
  CHECK_FALSE(h.run().resume("").empty());
  CHECK_FALSE(h.run().abort({}).error.empty());  // nothing left to abort
  h.restart();                                   // and so it stays after a restart
  CHECK(h.run().runs()["runs"][0]["status"] == "aborted");
  CHECK(h.run().status().state == proto::RunState::kIdle);
  CHECK(h.problems().empty());
}

TEST_CASE("run states: nudges at a connect prompt move the ball, within their limits",
          "[daemon][states]") {
  Harness h({"B1C1"}, {0});
  std::vector<std::string> answers;
  bool nudged = false;
  h.at_prompt = [&](const json& p) {
    if (p["action"] != "connect" || nudged) return true;
    nudged = true;
    h.expect(!h.run().nudge(1, 6).empty(), "a 6 mm nudge accepted (at most 5 mm a time)");
    h.expect(!h.run().nudge(2, 1).empty(), "a nudge for another shell's prompt accepted");
    h.expect(h.run().nudge(1, 2).empty(), "a 2 mm nudge refused");
    return false;  // confirmed below, once the nudge has moved
  };
  REQUIRE(h.run().start(h.plan()).empty());
  REQUIRE(h.waitState({"awaiting_confirm"}, 30) == "awaiting_confirm");
  // A nudge creeps in steps of the detached threshold, each watched: seconds for 5 mm.
  for (int i = 0; i < 1000 && h.events("nudged").empty(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  REQUIRE(h.events("nudged").size() == 1);
  CHECK(h.events("nudged")[0]["mm"] == 2.0);
  CHECK(h.run().nudge(1, 5).empty());
  for (int i = 0; i < 1000 && h.events("nudged").size() < 2; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  CHECK_FALSE(h.run().nudge(1, 4).empty());  // 11 mm in all for this connection
  // Back to where the plan put the ball: the bar, attached, then reads near zero.
  for (const double mm : {-5.0, -2.0}) {
    const std::size_t before = h.events("nudged").size();
    REQUIRE(h.run().nudge(1, mm).empty());
    for (int i = 0; i < 1000 && h.events("nudged").size() == before; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  CHECK(h.events("nudged").size() == 4);
  h.cell().attach(1, 1, 0);
  REQUIRE(h.run().confirm(1).empty());
  REQUIRE(h.waitState({"done", "paused", "error"}) == "done");
  CHECK_FALSE(h.run().nudge(1, 1).empty());  // no prompt pending
  CHECK(h.problems().empty());
}

TEST_CASE("run states: a nudge with the bar already seated stops at once, the bar unharmed",
          "[daemon][states]") {
  Harness h({"B1C1"}, {0});
  std::mutex answer_mutex;  // the answer is written on the run thread
  std::optional<std::string> nudge_answer;
  const auto answer = [&] {
    std::lock_guard lock(answer_mutex);
    return nudge_answer;
  };
  bool nudged = false;  // run thread only
  h.at_prompt = [&](const json& p) {
    if (p["action"] != "connect" || nudged) return true;
    nudged = true;
    h.cell().attach(1, 1, 0);  // the operator seats the bar, then asks for a nudge anyway
    const std::string refused = h.run().nudge(1, 5);
    std::lock_guard lock(answer_mutex);
    nudge_answer = refused;
    return false;
  };
  REQUIRE(h.run().start(h.plan()).empty());
  REQUIRE(h.waitState({"awaiting_confirm"}, 30) == "awaiting_confirm");
  // Refused outright when the reading has left the free bar's; else it creeps and stops.
  for (int i = 0; i < 1000 && (!answer() || (answer()->empty() && h.events("nudged").empty())); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  REQUIRE(answer());
  INFO(*answer());
  if (answer()->empty()) {
    REQUIRE(h.events("nudge_stopped").size() == 1);
    CHECK(std::abs(h.events("nudge_stopped")[0]["moved_mm"].get<double>()) <= 0.51);
  } else {
    CHECK_THAT(*answer(), Catch::Contains("nudge refused"));
  }
  CHECK(h.cell().worstDeflection() < 0.6);  // 5 mm at full speed would have been 5 mm
  REQUIRE(h.run().confirm(1).empty());
  REQUIRE(h.waitState({"done", "paused", "error"}) == "done");
  CHECK(h.problems().empty());
}

TEST_CASE("run states: a detach confirmed with the bar still on is caught by a small step",
          "[daemon][states]") {
  Harness h({"B1C1", "B2C2"}, {0});
  bool fooled = false;
  h.at_prompt = [&](const json& p) {
    if (p["action"] != "detach" || fooled) return true;
    fooled = true;  // confirmed, the bar left on
    h.expect(h.run().confirm(p["shell"].get<int>()).empty(), "confirm refused");
    return false;
  };
  REQUIRE(h.run().start(h.plan()).empty());
  REQUIRE(h.waitState({"paused", "done", "error"}) == "paused");
  const std::string reason = h.seen("STATE").back()["reason"];
  CHECK_THAT(reason, Catch::Contains("still on the robot"));
  CHECK(h.run().status().bar_attached);
  CHECK(h.cell().attached());
  CHECK(h.cell().worstDeflection() < 0.7);  // the probe's half millimetre, not a whole move
  // Resumed, the detach is asked again; done properly, the run goes on to the end.
  REQUIRE(h.run().resume("").empty());
  REQUIRE(h.waitState({"paused", "done", "error"}) == "done");
  CHECK(h.seen("SAMPLE").size() == static_cast<std::size_t>(h.points()));
  CHECK(h.events("detach_probe").size() >= 3);
  CHECK(h.problems().empty());
}

TEST_CASE(
    "run states: a garbled samples row pauses a resume with the way on, not 'resume continues'",
    "[daemon][states]") {
  Harness h({"B1C1", "B2C2"}, {0});
  int connects = 0;
  h.at_prompt = [&](const json& p) {
    if (p["action"] == "connect" && ++connects == 2) {  // after shell 1's points
      h.expect(h.run().pause("break").empty(), "pause refused");
      return false;
    }
    return true;
  };
  REQUIRE(h.run().start(h.plan()).empty());
  REQUIRE(h.waitState({"paused", "done", "error"}) == "paused");
  const std::string id = h.run().status().resumable;
  { std::ofstream(h.runDir(id) + "/samples.csv", std::ios::app) << "1,not,a,row\n"; }
  for (int resume = 0; resume < 2; ++resume) {  // and the same again: nothing moved meanwhile
    REQUIRE(h.run().resume("").empty());
    REQUIRE(h.waitState({"paused", "done", "error"}) == "paused");
    const std::string reason = h.seen("STATE").back()["reason"];
    CHECK_THAT(reason, Catch::Contains("samples.csv"));
    CHECK_THAT(reason, Catch::Contains("resume cannot go on until that file is repaired"));
    CHECK_THAT(reason, !Catch::Contains("resume continues"));
  }
  CHECK(h.problems().empty());
}

TEST_CASE("run states: two bar extensions make sets 1 and 2, the second predicted by the first",
          "[daemon][states]") {
  Harness h({"B1C1", "B2C2", "B3C3"}, {0, 100});
  REQUIRE(h.run().start(h.plan()).empty());
  REQUIRE(h.waitState({"done", "paused", "error"}, 120) == "done");
  const auto results = h.seen("RESULT");
  REQUIRE(results.size() == 2);
  CHECK(results[0]["set"] == 1);
  CHECK(results[0]["extension_mm"] == 0.0);
  CHECK(results[1]["set"] == 2);
  CHECK(results[1]["extension_mm"] == 100.0);
  CHECK(results[1].contains("prediction"));
  CHECK(h.events("set_complete").size() == 2);
  CHECK(h.problems().empty());
}

TEST_CASE("run states: a model error keeps the bar centred by corrective moves and refits",
          "[daemon][states]") {
  Harness h({"B1C1", "B2C2"}, {0}, 2.5);
  REQUIRE(h.run().start(h.plan()).empty());
  REQUIRE(h.waitState({"done", "paused", "error"}, 120) == "done");
  CHECK_FALSE(h.events("recentre").empty());
  CHECK_FALSE(h.events("replan").empty());  // published, so /metrics counts them
  CHECK(h.cell().worstDeflection() < 1.8);  // never past the hard limit
  CHECK(h.seen("SAMPLE").size() == static_cast<std::size_t>(h.points()));
  CHECK(h.problems().empty());
}

TEST_CASE("run states: a controller fault pauses the run wherever it comes, resume finishes it",
          "[daemon][states]") {
  // The first move goes to the connect pose, the next ones nudge nothing and measure.
  for (const int nth : {1, 3, 12, 40}) {
    DYNAMIC_SECTION("fault at move " << nth) {
      Harness h({"B1C1", "B2C2"}, {0});
      h.cell().failMove(nth, "Arm power off");
      REQUIRE(h.run().start(h.plan()).empty());
      REQUIRE(h.waitState({"paused", "done", "error"}) == "paused");
      CHECK_THAT(h.seen("STATE").back()["reason"].get<std::string>(),
                 Catch::Contains("Arm power off"));
      CHECK(h.cell().halts() >= 1);
      REQUIRE(h.run().resume("").empty());
      REQUIRE(h.waitState({"paused", "done", "error"}) == "done");
      const auto samples = h.seen("SAMPLE");
      CHECK(samples.size() == static_cast<std::size_t>(h.points()));
      CHECK(pointsOf(samples).size() == samples.size());  // nothing measured twice
      CHECK_FALSE(h.cell().attached());
      CHECK(h.problems().empty());
    }
  }
}
