// Motion through vias without stopping: the VAL II driver's path program (EDIT, MOVE lines, E,
// EXECUTE) against robocal-cellsim over real pseudo-terminals.
#include "cellsim_process.hpp"

#include <robocal/drivers/val.hpp>

#include <catch2/catch.hpp>

#include <cmath>

using namespace robocal::drivers;
using robocal::test::CellSimProcess;

namespace {

const Joints6& kStart = robocal::test::kCellSimStart;
const auto maxDiff = robocal::test::maxJointDiff;

// Three steps from the start, all in one sense of every joint (the vias are not corners to stop
// at): 10 deg each of joint 1.
const std::vector<Joints6> kPath{
    {10, 47, -88, 0, 45, 0}, {20, 50, -86, 2, 45, 0}, {30, 52, -85, 4, 44, 0}};

}  // namespace

TEST_CASE("VAL II: a path program moves through its vias without stopping",
          "[drivers][val][paths]") {
  CellSimProcess sim({"--time-scale", "2", "--speed", "20", "--blend-deg", "2"});
  boost::asio::io_context io;
  ValConfig config = sim.driversConfig().val;
  config.poll_interval_s = 0.02;
  ValController val(io, config);
  val.connect();
  REQUIRE(val.offersPaths());
  val.setSpeed(20);
  // Every WHERE while the path runs: the arm never rests before the last step.
  std::vector<Joints6> polls;
  const WhereReply end =
      val.movePath(kPath, [&](const WhereReply& w) { polls.push_back(w.joints_deg); });
  CHECK(maxDiff(end.joints_deg, kPath.back()) <= 0.006);
  REQUIRE(polls.size() >= 10);
  int still_on_the_way = 0;
  bool passed_middle = false;
  for (std::size_t k = 1; k < polls.size(); ++k) {
    if (maxDiff(polls[k], kPath.back()) > 0.5 && maxDiff(polls[k], polls[k - 1]) < 0.005)
      ++still_on_the_way;
    passed_middle = passed_middle || maxDiff(polls[k], kPath[1]) < 1.0;
  }
  CHECK(still_on_the_way == 0);
  CHECK(passed_middle);
  CHECK(sim.status("paths") == "1");
  CHECK(sim.status("moves") == "1");

  // A second path from there, and a plain move back: the monitor is out of the editor.
  const std::vector<Joints6> back{kPath[1], kPath[0]};
  CHECK(maxDiff(val.movePath(back).joints_deg, kPath[0]) <= 0.006);
  CHECK(maxDiff(val.moveJoints(kStart).joints_deg, kStart) <= 0.006);
  CHECK(sim.status("paths") == "2");
  CHECK(val.stats().controller_errors == 0);
}

TEST_CASE("VAL II: a path that cannot run moves nothing and leaves the monitor usable",
          "[drivers][val][paths]") {
  CellSimProcess sim({"--time-scale", "20"});
  boost::asio::io_context io;
  ValConfig config = sim.driversConfig().val;

  SECTION("a step outside the joint limits: refused at EXECUTE") {
    ValController val(io, config);
    val.connect();
    CHECK_THROWS_AS(val.movePath({kPath[0], {0, -80, -90, 0, 45, 0}}), OutOfRangeError);
    CHECK(maxDiff(val.where().joints_deg, kStart) < 0.006);
    CHECK(sim.status("moves") == "0");
  }
  SECTION("a dialect without path programs says so before sending anything") {
    config.path_execute_command.clear();
    ValController val(io, config);
    val.connect();
    CHECK_FALSE(val.offersPaths());
    try {
      val.movePath(kPath);
      FAIL("no error");
    } catch (const DriverError& e) {
      CHECK_THAT(e.what(), Catch::Contains("val.path_execute_command"));
    }
    CHECK(val.stats().commands <= 2);  // the wake-up only
    CHECK(sim.status("moves") == "0");
  }
  SECTION("abort stops a running path") {
    ValController val(io, config);
    val.connect();
    val.setSpeed(5);
    struct Stop {};  // how the daemon's watch ends a motion: thrown from the progress callback
    int polls = 0;
    CHECK_THROWS_AS(val.movePath(kPath,
                                 [&](const WhereReply&) {
                                   if (++polls == 3) throw Stop{};
                                 }),
                    Stop);
    val.abort();
    CHECK(sim.status("moving") == "0");
    CHECK(maxDiff(val.where().joints_deg, kPath.back()) > 1);
  }
}

TEST_CASE("VAL II: a program line refused leaves the editor and runs nothing",
          "[drivers][val][paths]") {
  // Command 1 is EDIT, command 2 the first MOVE line: the controller refuses it.
  CellSimProcess sim({"--time-scale", "20", "--val-error-on-command", "2", "--val-error-text",
                      "Invalid program step"});
  boost::asio::io_context io;
  ValController val(io, sim.driversConfig().val);
  val.connect();
  CHECK_THROWS_AS(val.movePath(kPath), ControllerError);
  CHECK(sim.status("moves") == "0");
  // WHERE is a monitor command again, not a program line, and the arm moves as before.
  CHECK(maxDiff(val.where().joints_deg, kStart) < 0.006);
  CHECK(maxDiff(val.moveJoints(kPath[0]).joints_deg, kPath[0]) <= 0.006);
  CHECK(sim.status("paths") == "0");
}
