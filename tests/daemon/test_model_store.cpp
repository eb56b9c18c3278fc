// The daemon's model versions on their own: numbering, activation, history, and damaged files
// skipped rather than fatal, across restarts (a new ModelStore on the same folder).
#include <catch2/catch.hpp>

#include "../cli/cli_helpers.hpp"

#include <robocal/daemon/model_store.hpp>
#include <robocal/robot/puma560.hpp>

#include <fstream>

using namespace robocal;
using namespace robocal::test;
using Catch::Matchers::Contains;

namespace {

proto::ModelEntry entry(const std::string& run, bool usable) {
  proto::ModelEntry e;
  e.date_utc = "2026-12-02T08:00:00Z";
  e.run = run;
  e.set = 1;
  e.samples = 800;
  e.fit_rms_mm = 0.08;
  e.rank = 36;
  e.usable = usable;
  if (!usable) e.problems = {"rank 30 of 36"};
  e.work_volume_error_mm = 0.05;
  return e;
}

}  // namespace

TEST_CASE("model versions: numbered, activated, checked, and kept across a restart") {
  TempDir dir;
  Model m = puma560NominalModel();
  m.joints[1].offset_deg = 0.03;
  {
    daemon::ModelStore store(dir.path.string());
    CHECK(store.list().models.empty());
    std::string problem;
    CHECK_FALSE(store.active(&problem));
    CHECK_THAT(problem, Contains("no model is active"));
    CHECK(store.add(m, entry("r1", true)) == 1);
    CHECK(store.add(m, entry("r2", false)) == 2);
    CHECK_THAT(store.activate(3), Contains("no model version 3"));
    CHECK_THAT(store.activate(2), Contains("not usable"));
    CHECK(store.activate(1).empty());
    store.addCheck(1, {"r3", "2026-12-03T08:00:00Z", "pass", 0.09});
    store.addCheck(1, {"r4", "2026-12-04T08:00:00Z", "fail", 0.31});
  }
  daemon::ModelStore again(dir.path.string());
  const proto::Models list = again.list();
  REQUIRE(list.models.size() == 2);
  CHECK(list.active == 1);
  CHECK(list.models[0].active);
  CHECK_FALSE(list.models[1].active);
  CHECK(list.models[1].problems == std::vector<std::string>{"rank 30 of 36"});
  REQUIRE(list.models[0].checks.size() == 2);
  CHECK(list.models[0].checks[1].verdict == "fail");
  const auto active = again.active();
  REQUIRE(active);
  CHECK(active->version == 1);
  CHECK(active->model.joints[1].offset_deg == Approx(0.03));
  // A new fit gets the next number; the old files are untouched.
  CHECK(again.add(m, entry("r5", true)) == 3);
  CHECK(again.list().models.size() == 3);
}

TEST_CASE("model versions: damaged files are skipped, never fatal") {
  TempDir dir;
  daemon::ModelStore store(dir.path.string());
  const Model m = puma560NominalModel();
  REQUIRE(store.add(m, entry("r1", true)) == 1);
  REQUIRE(store.add(m, entry("r2", true)) == 2);
  REQUIRE(store.activate(2).empty());
  std::ofstream(dir / "models/model-0001.summary.json") << "{\"version\": ";
  std::ofstream(dir / "models/active.json") << "not json";
  daemon::ModelStore again(dir.path.string());
  const proto::Models list = again.list();
  REQUIRE(list.models.size() == 1);  // version 1's summary is unreadable
  CHECK(list.models[0].version == 2);
  CHECK_FALSE(list.active);  // doubt: no active model rather than a guess
  CHECK_FALSE(again.active());
  CHECK_THAT(again.activate(1), Contains("cannot be read"));
  CHECK(again.activate(2).empty());
  CHECK(again.active()->version == 2);
  // A damaged model file with a good summary cannot be activated.
  std::ofstream(dir / "models/model-0002.json") << "{}";
  daemon::ModelStore third(dir.path.string());
  CHECK_FALSE(third.activate(2).empty());
}
