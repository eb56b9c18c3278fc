// The VAL driver against the behaviours of hardware.md's evidence that the first simulator never
// produced, each spoken by robocal-cellsim over real pseudo-terminals: the "*" prompt while a move
// runs, an E-stop reported behind it, a synchronous DO MOVE, completion lines inside a reply, a
// controller that just booted and asks a question, and each dialect preset end to end.
#include "cellsim_process.hpp"

#include <robocal/drivers/diagnose.hpp>
#include <robocal/drivers/val.hpp>

#include <catch2/catch.hpp>

#include <cmath>
#include <thread>

using namespace robocal::drivers;
using robocal::test::CellSimProcess;

namespace {

const Joints6& kStart = robocal::test::kCellSimStart;
const auto maxDiff = robocal::test::maxJointDiff;

std::string dialectJson(const std::string& dialect) {
  return R"({"val": {"dialect": ")" + dialect + R"("}})";
}

}  // namespace

TEST_CASE("VAL dialects: the '*' prompt while a move runs ends every reply", "[drivers][val]") {
  CellSimProcess sim({"--time-scale", "1", "--speed", "20"});
  boost::asio::io_context io;
  ValController val(io, sim.driversConfig().val);
  val.connect();
  const Joints6 far{30, 45, -90, 0, 45, 0};  // 30 deg at 12 deg/s: 2.5 s
  val.startMove(far);
  CHECK(sim.status("moving") == "1");
  const Joints6 mid = val.where().joints_deg;  // its reply ends in "*"
  CHECK(mid[0] > 0);
  CHECK(mid[0] < 29);

  CHECK(maxDiff(val.waitForMotion(far).joints_deg, far) <= 0.006);
  CHECK(val.stats().timeouts == 0);
}

TEST_CASE("VAL dialects: a config that knows only '.' sees the '*' and says so", "[drivers][val]") {
  CellSimProcess sim({"--time-scale", "1", "--speed", "20"});
  boost::asio::io_context io;
  auto dot_only = sim.driversConfig().val;
  dot_only.prompt = {"."};
  ValController val(io, dot_only);
  val.connect();
  try {
    val.command(val.dialect().moveCommand({30, 45, -90, 0, 45, 0}), 0.5);
    FAIL("a reply ending in '*' was taken as complete");
  } catch (const TimeoutError& e) {
    CHECK_THAT(e.what(), Catch::Contains("it shows '*'"));
    CHECK_THAT(e.what(), Catch::Contains("add it to val.prompt"));
  }
}

TEST_CASE("VAL dialects: an E-stop while '*' shows raises the arm-power-off error",
          "[drivers][val]") {
  CellSimProcess sim({"--time-scale", "1", "--speed", "20", "--estop-on-move", "1"});
  boost::asio::io_context io;
  ValController val(io, sim.driversConfig().val);
  val.connect();
  try {
    val.moveJoints({20, 45, -90, 0, 45, 0});
    FAIL("the move went on through an E-stop");
  } catch (const ArmPowerOffError& e) {
    CHECK(e.controllerMessage() == "Arm power off");  // the controller's words
  }
  CHECK(sim.status("estop") == "1");
}

TEST_CASE("VAL dialects: a 90 deg synchronous move at SPEED 10 takes its time", "[drivers][val]") {
  // 90 deg at 6 deg/s, 3 times faster: 5 s before the prompt comes back, the same as the old
  // fixed move_timeout_s and more than the 2 s set here.
  CellSimProcess sim({"--time-scale", "3", "--val-sync-moves"});
  boost::asio::io_context io;
  auto config = sim.driversConfig().val;
  config.move_timeout_s = 2;
  const Joints6 target{90, 45, -90, 0, 45, 0};

  SECTION("the deadline comes from the move: no timeout") {
    ValController val(io, config);
    val.connect();
    val.setSpeed(10);
    val.where();  // the joints the deadline is measured from
    CHECK(val.moveCommandTimeout(target) == Approx(2 + 90 / (20 * 0.1)));
    CHECK(maxDiff(val.moveJoints(target).joints_deg, target) <= 0.006);
    CHECK(val.stats().timeouts == 0);
    CHECK(val.stats().move_timeouts_watched == 0);
    // And back: the second move after a finished one.
    CHECK(maxDiff(val.moveJoints(kStart).joints_deg, kStart) <= 0.006);
  }
  SECTION("a deadline too short: the driver goes on watching WHERE instead of failing") {
    config.slowest_joint_speed_deg_s = 1000;  // claims the move takes 0.9 s
    ValController val(io, config);
    val.connect();
    val.setSpeed(10);
    val.where();
    CHECK(maxDiff(val.moveJoints(target).joints_deg, target) <= 0.006);
    CHECK(val.stats().move_timeouts_watched == 1);
    CHECK(maxDiff(val.where().joints_deg, target) <= 0.006);  // in step again
  }
  SECTION("a move command lost on a stalled line fails at move_timeout_s, not motion_timeout_s") {
    config.motion_timeout_s = 60;  // the deadline while SPEED is unknown: far longer than 2 s
    ValController val(io, config);
    val.connect();
    REQUIRE(val.moveCommandTimeout(target) == Approx(60));
    REQUIRE(sim.control("fault stall val 3").rfind("ok", 0) == 0);
    const auto start = std::chrono::steady_clock::now();
    CHECK_THROWS_AS(val.moveJoints(target), TimeoutError);
    const double waited_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    CHECK(waited_s < 10);  // 2 s and a margin for a loaded machine; never the 60 s
    CHECK(val.stats().timeouts == 1);
    CHECK(val.stats().move_timeouts_watched == 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(1200));  // the stall ends
    CHECK(maxDiff(val.where().joints_deg, kStart) <= 0.006);       // the arm never moved
  }
}

TEST_CASE("VAL dialects: completion lines are dropped, inside a reply too", "[drivers][val]") {
  CellSimProcess sim({"--time-scale", "20", "--val-completion-lines"});
  boost::asio::io_context io;
  ValController val(io, sim.driversConfig().val);
  val.connect();
  REQUIRE(sim.control("fault completion").rfind("ok", 0) == 0);
  CHECK(maxDiff(val.where().joints_deg, kStart) <= 0.006);  // the line sat between its blocks
  CHECK(val.stats().ignored_lines == 1);
  const Joints6 target{5, 40, -85, 0, 45, 0};
  CHECK(maxDiff(val.moveJoints(target).joints_deg, target) <= 0.006);
  CHECK(maxDiff(val.moveJoints(kStart).joints_deg, kStart) <= 0.006);
  CHECK(val.stats().ignored_lines >= 2);  // each move's own completion line
  CHECK(val.stats().controller_errors == 0);
}

TEST_CASE("VAL dialects: a controller that asks a question is diagnosed, never answered",
          "[drivers][val]") {
  CellSimProcess sim({"--val-boot-question"});
  boost::asio::io_context io;
  const auto config = sim.driversConfig().val;
  const Diagnosis d = diagnoseVal(io, config);
  CHECK(d.verdict == Verdict::kQuestion);
  CHECK_THAT(d.message, Catch::Contains("Load VAL from floppy (Y/N)?"));
  CHECK_THAT(d.message, Catch::Contains("never answers"));
  CHECK_THAT(d.message, !Catch::Contains("val.prompt"));

  {
    ValController val(io, config);
    try {
      val.connect();
      FAIL("connected to a controller that asks a question");
    } catch (const QuestionError& e) {
      CHECK(e.controllerMessage() == "Load VAL from floppy (Y/N)?");
    }
  }
  // Still asking: the driver did not answer.
  CHECK(diagnoseVal(io, config).verdict == Verdict::kQuestion);
  {
    // The operator answers at the terminal (here through the driver's raw command).
    ValController val(io, config);
    CHECK_THROWS_AS(val.connect(), QuestionError);
    val.command("N", 2);
    CHECK(maxDiff(val.where().joints_deg, kStart) <= 0.006);
  }
  CHECK(diagnoseVal(io, config).verdict == Verdict::kOk);
}

TEST_CASE("VAL dialects: each preset connects, reads WHERE, moves, reports errors and E-stop",
          "[drivers][val]") {
  for (const std::string dialect : {"val2", "vplus", "kawasaki-as"}) {
    DYNAMIC_SECTION(dialect) {
      CellSimProcess sim({"--time-scale", "20"}, dialectJson(dialect));
      boost::asio::io_context io;
      ValController val(io, sim.driversConfig().val);
      REQUIRE(val.dialect().config().dialect == dialect);
      val.connect();
      const WhereReply w = val.where();
      CHECK(maxDiff(w.joints_deg, kStart) < 0.006);
      CHECK(w.location.has_value());
      const Joints6 target{-10, 50, -95, 5, 40, 15};
      CHECK(maxDiff(val.moveJoints(target).joints_deg, target) <= 0.006);
      CHECK_THROWS_AS(val.moveJoints({0, -80, -90, 0, 45, 0}), OutOfRangeError);
      REQUIRE(sim.control("estop").rfind("ok", 0) == 0);
      CHECK_THROWS_AS(val.moveJoints(kStart), ArmPowerOffError);
      REQUIRE(sim.control("reset").rfind("ok", 0) == 0);
      CHECK(maxDiff(val.moveJoints(kStart).joints_deg, kStart) <= 0.006);
      if (dialect == "kawasaki-as") CHECK(val.stats().ignored_lines >= 2);
    }
  }
}
