// The health check through the whole product: robocal-cellsim (the true robot on ptys), robocald
// running the check's plan over TCP, the operator answering its prompts, and the verdict in the
// run folder, the event log, the model's history and on the protocol. Twice: the true robot as the
// active model passes; then the nominal model, which the robot no longer fits, fails.
#include <catch2/catch.hpp>

#include "sim_cell.hpp"

#include <robocal/daemon/model_store.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/planner/health_plan.hpp>

using namespace robocal;
using namespace robocal::test;
using json = nlohmann::json;
using Catch::Matchers::Contains;

namespace {

// A model as if a calibration had made it: its fit reached `rms_mm`.
Model asCalibrated(Model m, double rms_mm) {
  ModelProvenance p;
  p.date_utc = "2026-12-02T08:00:00Z";
  p.rms_mm = rms_mm;
  p.rank = 36;
  p.expected_rank = 36;
  m.provenance = p;
  return m;
}

proto::ModelEntry summary(const std::string& run) {
  proto::ModelEntry e;
  e.date_utc = "2026-12-02T08:00:00Z";
  e.run = run;
  e.set = 1;
  e.samples = 500;
  e.fit_rms_mm = 0.05;
  e.rank = 36;
  return e;
}

// Starts the check, operates it to its end and returns the CHECK it published.
json runCheck(Cell& cell, proto::Client& c) {
  const json ack =
      c.request({{"cmd", "start"}, {"check", true}, {"token", cell.daemon->token()}}, 60, "ACK");
  REQUIRE(ack["class"] == "ACK");
  std::vector<json> seen;
  REQUIRE(cell.operate(c, {"done", "paused", "error", "aborted"}, 240, &seen) == "done");
  for (int i = 0; i < 100; ++i) {  // the verdict follows the run's end
    for (const json& o : seen)
      if (o["class"] == "CHECK") return o;
    if (auto o = c.read(0.2)) seen.push_back(*o);
  }
  FAIL("no CHECK after the check run");
  return {};
}

}  // namespace

TEST_CASE(
    "a health check run over cellsim: pass with a model that fits, fail with one that does not",
    "[e2e]") {
  Cell cell({"B1C2", "B2C3", "B3C1"}, 21, true, 60);
  const int fits = [&] {
    daemon::ModelStore store(cell.daemon->dataDir());
    store.add(asCalibrated(loadModelFile(cell.truth_path), 0.05), summary("truth"));
    return store.add(asCalibrated(loadModelFile(kModel), 0.05), summary("nominal"));
  }();
  REQUIRE(fits == 2);
  auto c = cell.daemon->client();
  c->send({{"cmd", "watch"}, {"enable", true}});
  CHECK(c->request({{"cmd", "check_result"}}, 10, "CHECK")["available"] == false);
  // No verdict without a model to judge.
  CHECK_THAT(c->request({{"cmd", "start"}, {"check", true}, {"token", cell.daemon->token()}}, 10,
                        "ERROR")["message"]
                 .get<std::string>(),
             Contains("no model is active"));

  REQUIRE(c->request({{"cmd", "activate"}, {"version", 1}, {"token", cell.daemon->token()}}, 10,
                     "ACK")["class"] == "ACK");
  const json pass = runCheck(cell, *c);
  INFO(pass.dump(1));
  CHECK(pass["status"] == "pass");
  CHECK(pass["model_version"] == 1);
  CHECK(pass["verdict"]["samples"].get<int>() >= kHealthCheckPoints - 2);
  CHECK(pass["verdict"]["extensions_mm"] == json::array({75.0}));
  CHECK(pass["verdict"]["connections"].size() == kHealthCheckShells);
  const std::string run = pass["run"];
  CHECK(json::parse(readTextFile(cell.runDir(run) + "/check.json")) == pass);
  CHECK_THAT(readTextFile(cell.runDir(run) + "/events.jsonl"), Contains("\"health_check\""));
  // A check makes no new model.
  const json models = c->request({{"cmd", "models"}}, 10, "MODELS");
  REQUIRE(models["models"].size() == 2);
  REQUIRE(models["models"][0]["checks"].size() == 1);
  CHECK(models["models"][0]["checks"][0]["verdict"] == "pass");

  // The second check, of a model the robot does not fit.
  REQUIRE(c->request({{"cmd", "activate"}, {"version", 2}, {"token", cell.daemon->token()}}, 10,
                     "ACK")["class"] == "ACK");
  const json fail = runCheck(cell, *c);
  INFO(fail.dump(1));
  CHECK(fail["status"] == "fail");
  CHECK(fail["verdict"]["rms_ratio"].get<double>() > 1.5);
  CHECK_FALSE(fail["verdict"]["moved"].empty());
  CHECK(c->request({{"cmd", "check_result"}}, 10, "CHECK")["run"] == fail["run"]);

  // After a restart the latest verdict is served from the run folder, and robocal prints it.
  c.reset();
  cell.daemon->stop();
  cell.daemon->start();
  CHECK(cell.daemon->client()->request({{"cmd", "check_result"}}, 10, "CHECK")["run"] ==
        fail["run"]);
  const auto printed = runRobocal("check-result --port " + std::to_string(cell.daemon->port()));
  CHECK(printed.exit_code == 5);
  CHECK_THAT(printed.output, Contains("FAIL"));
}
