// Test helper: a whole simulated cell for the end-to-end tests: robocal-cellsim (a perturbed true
// robot on ptys), robocald pointed at it with a small cell file, and an operator that answers
// every prompt through cellsim's control socket, as a person at the cell would.
#pragma once

#include "../cli/cli_helpers.hpp"
#include "../drivers/cellsim_process.hpp"
#include "daemon_process.hpp"

#include <robocal/sim/operator.hpp>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <fstream>
#include <functional>
#include <memory>
#include <set>
#include <string>
#include <vector>

namespace robocal::test {

// The time scales a bar-safety test runs at: real time and cellsim's 100x in the plain build;
// 100x only under the sanitizers, where real time costs minutes a test and adds no code path.
inline std::vector<double> testTimeScales() {
#ifdef ROBOCAL_SANITIZED
  return {100.0};
#else
  return {1.0, 100.0};
#endif
}

// How many events of this name a run's log holds.
inline int countEvents(const std::string& run_dir, const std::string& name) {
  std::ifstream in(run_dir + "/events.jsonl");
  int n = 0;
  for (std::string line; std::getline(in, line);)
    n += nlohmann::json::parse(line).value("event", "") == name;
  return n;
}

struct Cell {
  TempDir dir;
  std::string truth_path;
  std::unique_ptr<CellSimProcess> sim;
  std::unique_ptr<DaemonProcess> daemon;

  // The operator's answer to one prompt, in place of the right one when it returns true (a test
  // of a mistake: a free bar, a wrong chuck, a bar left on).
  std::function<bool(proto::Client&, const nlohmann::json& prompt)> mistake;

  // `daemon_keys` replace or add robocald config keys; `sim_args` are added to cellsim's (a later
  // option wins); `drivers_json` (a drivers config, e.g. a dialect) is given to both cellsim and
  // robocald; `model` is the arm's nominal model (the truth is it perturbed); `cell_patch` is
  // merged into the cell file (e.g. {"motion": {"through_vias": true}}).
  Cell(const std::vector<std::string>& connections, unsigned seed, bool centering = true,
       double lon_step_deg = 60, double time_scale = 50,
       const nlohmann::json& daemon_keys = nlohmann::json::object(),
       const std::vector<std::string>& sim_args = {}, const std::string& drivers_json = "",
       const std::string& model = kModel,
       const nlohmann::json& cell_patch = nlohmann::json::object()) {
    truth_path = dir / "truth.json";
    const auto r = runRobocal("simulate --model " + model + " --seed " + std::to_string(seed) +
                              " --connections B1C1 --points-per-shell 1 --out " + (dir / "x.csv") +
                              " --truth-out " + truth_path);
    REQUIRE(r.exit_code == 0);
    std::vector<std::string> args{
        "--model",    truth_path, "--time-scale", std::to_string(time_scale),
        "--bar-mode", "streamed", "--stream-hz",  "100",
        "--bar-mm",   "150",      "--range-mm",   "2.0",
        "--noise-mm", "0.03"};
    args.insert(args.end(), sim_args.begin(), sim_args.end());
    sim = std::make_unique<CellSimProcess>(args, drivers_json);
    nlohmann::json cell = smallCell(connections, {0}, lon_step_deg);
    cell.merge_patch(cell_patch);
    std::ofstream(dir / "cell.json") << cell.dump(1);
    nlohmann::json drivers = drivers::toJson(sim->driversConfig());
    drivers["bar"]["mode"] = "streamed";
    drivers["val"]["poll_interval_s"] = 0.01;
    nlohmann::json config{{"model", model},           {"cell", dir / "cell.json"},
                          {"settle_s", 0.02},         {"bar_window_s", 0.03},
                          {"bar_soft_limit_mm", 1.0}, {"bar_hard_limit_mm", 1.6},
                          {"centering", centering},   {"drivers", drivers}};
    config.update(daemon_keys);
    daemon = std::make_unique<DaemonProcess>(config);
    daemon->start();
  }

  // Acts as the operator until the run reaches one of `states` (returns it) or the time is up
  // (returns ""). Every object read lands in `seen`.
  std::string operate(proto::Client& c, const std::set<std::string>& states, double timeout_s,
                      std::vector<nlohmann::json>* seen = nullptr) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < deadline) {
      auto o = c.read(0.2);
      if (!o) continue;
      if (seen && (*o)["class"] != "BAR") seen->push_back(*o);
      const std::string cls = (*o)["class"];
      if (cls == "PROMPT" && !(mistake && mistake(c, *o)))
        sim::answerPrompt(
            c, proto::parseObject<proto::Prompt>(*o),
            [&](const std::string& cmd) { return sim->control(cmd); }, daemon->token(), 150);
      if (cls == "STATE" && states.count((*o)["to"])) {
        // Why the run stopped, in the report of any check on the state that follows.
        UNSCOPED_INFO("the run went " << (*o)["to"].get<std::string>() << ": "
                                      << o->value("reason", std::string("(no reason)")));
        return (*o)["to"];
      }
    }
    UNSCOPED_INFO("no state of interest within " << timeout_s << " s");
    return "";
  }

  std::string runDir(const std::string& id) const { return daemon->dataDir() + "/runs/" + id; }
};

}  // namespace robocal::test
