// The VAL II driver against robocal-cellsim over real pseudo-terminals.
#include "cellsim_process.hpp"

#include <robocal/drivers/val.hpp>

#include <catch2/catch.hpp>

#include <cmath>
#include <thread>

using namespace robocal::drivers;
using robocal::test::CellSimProcess;

namespace {

const Joints6& kStart = robocal::test::kCellSimStart;
const auto maxDiff = robocal::test::maxJointDiff;

}  // namespace

TEST_CASE("VAL II: connect, WHERE, move and WHERE round trip", "[drivers][val]") {
  CellSimProcess sim({"--time-scale", "20"});
  boost::asio::io_context io;
  ValController val(io, sim.driversConfig().val);
  val.connect();
  const WhereReply start = val.where();
  CHECK(maxDiff(start.joints_deg, kStart) < 0.006);
  REQUIRE(start.location.has_value());

  val.setSpeed(80);
  const Joints6 target{12.5, 30.25, -80, 10, 35.5, -20};
  int polls = 0;
  const WhereReply end = val.moveJoints(target, [&](const WhereReply&) { ++polls; });
  CHECK(maxDiff(end.joints_deg, target) <= 0.006);  // quantised to 0.01 deg
  CHECK(polls >= 2);
  CHECK(maxDiff(val.where().joints_deg, target) <= 0.006);

  // A second move from there, and back.
  CHECK(maxDiff(val.moveJoints(kStart).joints_deg, kStart) <= 0.006);
  CHECK(val.stats().controller_errors == 0);
  CHECK(val.stats().timeouts == 0);
}

TEST_CASE("VAL II: controller errors become typed errors", "[drivers][val]") {
  CellSimProcess sim({"--time-scale", "20"});
  boost::asio::io_context io;
  ValController val(io, sim.driversConfig().val);
  val.connect();

  SECTION("a target outside the joint limits") {
    CHECK_THROWS_AS(val.moveJoints({0, -80, -90, 0, 45, 0}), OutOfRangeError);
    // The controller stays usable.
    CHECK(maxDiff(val.where().joints_deg, kStart) < 0.006);
  }
  SECTION("an injected error reply") {
    REQUIRE(sim.control("fault error Servo fault joint 3").rfind("ok", 0) == 0);
    try {
      val.where();
      FAIL("no error");
    } catch (const ControllerError& e) {
      CHECK(e.controllerMessage() == "Servo fault joint 3");
      CHECK(dynamic_cast<const OutOfRangeError*>(&e) == nullptr);
    }
    CHECK(maxDiff(val.where().joints_deg, kStart) < 0.006);
  }
  SECTION("an unknown command") {
    CHECK_THROWS_AS(val.command("FROBNICATE", 2), ControllerError);
  }
  SECTION("a bad speed is refused before it is sent") {
    CHECK_THROWS_AS(val.setSpeed(150), DriverError);
  }
}

TEST_CASE("VAL II: E-stop during a move, then reset", "[drivers][val]") {
  CellSimProcess sim({"--time-scale", "2", "--estop-on-move", "1"});
  boost::asio::io_context io;
  ValController val(io, sim.driversConfig().val);
  val.connect();
  const Joints6 target{30, 45, -90, 0, 45, 0};
  CHECK_THROWS_AS(val.moveJoints(target), ArmPowerOffError);
  const WhereReply stopped = val.where();
  CHECK(maxDiff(stopped.joints_deg, target) > 1);  // stopped on the way
  CHECK_THROWS_AS(val.moveJoints(target), ArmPowerOffError);
  REQUIRE(sim.control("reset") == "ok reset");
  CHECK(maxDiff(val.moveJoints(target).joints_deg, target) <= 0.006);
}

TEST_CASE("VAL II: abort stops a slow move, a move that takes too long is a MotionError",
          "[drivers][val]") {
  CellSimProcess sim({"--time-scale", "1", "--speed", "10"});
  auto config = sim.driversConfig().val;
  config.motion_timeout_s = 0.4;
  boost::asio::io_context io;
  ValController val(io, config);
  val.connect();
  const Joints6 target{40, 45, -90, 0, 45, 0};  // 40 deg at 6 deg/s: about 7 s
  CHECK_THROWS_AS(val.moveJoints(target), MotionError);
  val.abort();
  const Joints6 a = val.where().joints_deg;
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const Joints6 b = val.where().joints_deg;
  CHECK(maxDiff(a, b) < 0.006);    // still
  CHECK(maxDiff(b, target) > 30);  // short of the target
  CHECK(b[0] > 0.5);               // but it did move
}

TEST_CASE("VAL II: a stalled controller times out, then is usable again", "[drivers][val]") {
  CellSimProcess sim({"--time-scale", "20"});
  auto config = sim.driversConfig().val;
  config.where_timeout_s = 0.5;
  boost::asio::io_context io;
  ValController val(io, config);
  val.connect();
  REQUIRE(sim.control("fault stall val 1.0").rfind("ok", 0) == 0);
  CHECK_THROWS_AS(val.where(), TimeoutError);
  CHECK(val.stats().timeouts == 1);
  std::this_thread::sleep_for(std::chrono::milliseconds(700));
  CHECK(maxDiff(val.where().joints_deg, kStart) < 0.006);
}

TEST_CASE("VAL II: disconnect and reconnect (adapter re-plugged)", "[drivers][val]") {
  CellSimProcess sim(
      {"--time-scale", "20", "--val-disconnect-after", "2", "--reconnect-after-s", "0.5"});
  boost::asio::io_context io;
  ValController val(io, sim.driversConfig().val);
  val.connect();  // command 1 is the wake-up (empty lines are not counted)
  val.where();    // 1
  val.where();    // 2
  CHECK_THROWS_AS(val.where(), DisconnectedError);  // the 3rd: the pty goes away
  CHECK_FALSE(val.isConnected());
  val.reconnect(10);
  CHECK(maxDiff(val.where().joints_deg, kStart) < 0.006);

  // And through the control channel.
  REQUIRE(sim.control("fault disconnect val 0.3").rfind("ok", 0) == 0);
  CHECK_THROWS_AS(val.where(), DisconnectedError);
  val.reconnect(10);
  CHECK(maxDiff(val.moveJoints({5, 45, -90, 0, 45, 0}).joints_deg, {5, 45, -90, 0, 45, 0}) <=
        0.006);
}

TEST_CASE("VAL II: dialect variants the simulator speaks", "[drivers][val]") {
  SECTION("no echo, CR line endings, HAND column, other widths and decimals") {
    CellSimProcess sim({"--time-scale", "20", "--val-no-echo", "--val-eol", "cr", "--val-hand",
                        "--val-decimals", "2", "--val-column-width", "13"});
    boost::asio::io_context io;
    ValController val(io, sim.driversConfig().val);
    val.connect();
    const Joints6 target{-10, 50, -95, 5, 40, 15};
    CHECK(maxDiff(val.moveJoints(target).joints_deg, target) <= 0.006);
  }
  SECTION("a blank HAND column, LF endings, narrow columns") {
    CellSimProcess sim({"--time-scale", "20", "--val-hand-blank", "--val-eol", "lf",
                        "--val-column-width", "9", "--val-decimals", "4"});
    boost::asio::io_context io;
    ValController val(io, sim.driversConfig().val);
    val.connect();
    CHECK(maxDiff(val.where().joints_deg, kStart) < 0.006);
  }
  SECTION("a configured dialect: prompt, templates and headers from JSON") {
    const std::string json = R"({"val": {
        "prompt": ">",
        "move_joints_command": "DRIVEJ {j1} {j2} {j3} {j4} {j5} {j6}",
        "where_command": "W",
        "speed_command": "SPEED {speed} ALWAYS",
        "joint_headers": ["J1", "J2", "J3", "J4", "J5", "J6"]}})";
    CellSimProcess sim({"--time-scale", "20"}, json);
    boost::asio::io_context io;
    ValController val(io, sim.driversConfig().val);
    val.connect();
    val.setSpeed(75);
    const Joints6 target{3, 47, -88, 2, 44, 1};
    CHECK(maxDiff(val.moveJoints(target).joints_deg, target) <= 0.006);
  }
}

TEST_CASE("VAL II: wrong baud rate and missing port are explained", "[drivers][val]") {
  CellSimProcess sim;
  boost::asio::io_context io;
  SECTION("wrong baud") {
    auto config = sim.driversConfig().val;
    config.serial.baud = 4800;
    config.connect_timeout_s = 0.5;
    ValController val(io, config);
    try {
      val.connect();
      FAIL("connected at the wrong baud rate");
    } catch (const TimeoutError& e) {
      CHECK_THAT(e.what(), Catch::Contains("baud"));
    }
  }
  SECTION("no such port") {
    auto config = sim.driversConfig().val;
    config.serial.path = sim.dir() + "/nothing-here";
    ValController val(io, config);
    try {
      val.connect();
      FAIL("opened a missing port");
    } catch (const PortError& e) {
      CHECK_THAT(e.what(), Catch::Contains("no such port"));
    }
  }
}

TEST_CASE("VAL II: a progress callback that throws stops the wait, the driver stays usable",
          "[drivers][val]") {
  CellSimProcess sim({"--time-scale", "1", "--speed", "20"});
  boost::asio::io_context io;
  ValController val(io, sim.driversConfig().val);
  val.connect();
  struct Stop {};
  int polls = 0;
  CHECK_THROWS_AS(val.moveJoints({20, 45, -90, 0, 45, 0},
                                 [&](const WhereReply&) {
                                   if (++polls == 3) throw Stop{};
                                 }),
                  Stop);
  val.abort();
  const Joints6 here = val.where().joints_deg;
  CHECK(here[0] > 0);
  CHECK(here[0] < 19);
  CHECK(maxDiff(val.moveJoints({0, 45, -90, 0, 45, 0}).joints_deg, kStart) <= 0.006);
}

TEST_CASE("VAL II: garbled and lost WHERE lines during a move are asked again", "[drivers][val]") {
  CellSimProcess sim({"--time-scale", "20", "--val-garbage-every", "3", "--val-drop-every", "5"});
  boost::asio::io_context io;
  ValController val(io, sim.driversConfig().val);
  val.connect();
  const Joints6 target{8, 50, -85, 3, 40, -5};
  CHECK(maxDiff(val.moveJoints(target).joints_deg, target) <= 0.006);
  CHECK(maxDiff(val.moveJoints(kStart).joints_deg, kStart) <= 0.006);
  CHECK(val.stats().where_retries >= 1);
}

TEST_CASE("VAL II: a single WHERE with a lost or garbled line is a ProtocolError",
          "[drivers][val]") {
  CellSimProcess sim;
  boost::asio::io_context io;
  ValController val(io, sim.driversConfig().val);
  val.connect();
  REQUIRE(sim.control("fault drop val").rfind("ok", 0) == 0);
  CHECK_THROWS_AS(val.where(), ProtocolError);
  REQUIRE(sim.control("fault garbage val").rfind("ok", 0) == 0);
  CHECK_THROWS_AS(val.where(), ProtocolError);
  CHECK(maxDiff(val.where().joints_deg, kStart) <= 0.006);
}
