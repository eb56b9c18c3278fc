// The ball-bar reader driver against robocal-cellsim over real pseudo-terminals.
#include "cellsim_process.hpp"

#include <robocal/drivers/bar.hpp>
#include <robocal/drivers/val.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/kinematics/kinematics.hpp>

#include <catch2/catch.hpp>

#include <cmath>
#include <thread>

using namespace robocal::drivers;
using robocal::test::CellSimProcess;

namespace {
const Joints6 kStart{0, 45, -90, 0, 45, 0};

double trueLength(const robocal::Model& m, const Joints6& j, int ball, int chuck) {
  robocal::JointsDeg r;
  for (int i = 0; i < 6; ++i) r[i] = j[i];
  return robocal::Kinematics(m).barLength(r, m.balls_mm[ball], m.chucks_mm[chuck]);
}
}  // namespace

TEST_CASE("Bar: polled readings follow the true bar length", "[drivers][bar]") {
  CellSimProcess sim({"--time-scale", "20", "--noise-mm", "0.001"});
  REQUIRE(sim.control("connect B2C3 bar_mm=here").rfind("ok", 0) == 0);
  const auto config = sim.driversConfig();
  boost::asio::io_context io;
  BarReader bar(io, config.bar);
  bar.connect();
  const BarReading first = bar.read();
  CHECK(first.kind == BarLineKind::kReading);
  CHECK(std::abs(first.value_mm) < 0.01);
  const BarReading second = bar.read();
  CHECK(second.sequence > first.sequence);
  CHECK(second.time >= first.time);
  CHECK_FALSE(bar.isStale());

  // Move a little: the bar reads the change of the true length.
  boost::asio::io_context val_io;
  ValController val(val_io, config.val);
  val.connect();
  const Joints6 target{0.3, 45.2, -90.1, 0, 45, 0};
  val.moveJoints(target);
  const auto model = robocal::loadModelFile(ROBOCAL_SOURCE_DIR "/config/puma560-paper.json");
  const double expected = trueLength(model, target, 1, 2) - trueLength(model, kStart, 1, 2);
  REQUIRE(std::abs(expected) > 0.05);
  REQUIRE(std::abs(expected) < 1.5);
  CHECK(bar.readValueMm() == Approx(expected).margin(0.01));
}

TEST_CASE("Bar: over range is reported and the simulator records the break", "[drivers][bar]") {
  CellSimProcess sim({"--time-scale", "20", "--range-mm", "1.0"});
  REQUIRE(sim.control("connect B1C1 bar_mm=here").rfind("ok", 0) == 0);
  const auto config = sim.driversConfig();
  boost::asio::io_context io;
  BarReader bar(io, config.bar);
  bar.connect();
  CHECK(bar.read().kind == BarLineKind::kReading);
  ValController val(io, config.val);
  val.connect();
  val.moveJoints({0, 50, -90, 0, 45, 0});  // about 48 mm longer
  const BarReading r = bar.read();
  CHECK(r.kind == BarLineKind::kOverRange);
  CHECK_THROWS_AS(bar.readValueMm(), BarStatusError);
  CHECK(bar.stats().over_range >= 2);
  CHECK(sim.status("broken_events") == "1");
  CHECK_THAT(sim.control("events"), Catch::StartsWith("ok 1 time_s=") &&
                                        Catch::Contains("connection=B1C1,deflection_mm=+"));
  // Back into range: readings again.
  val.moveJoints(kStart);
  CHECK(bar.read().kind == BarLineKind::kReading);
}

TEST_CASE("Bar: garbage and cut-off lines are counted and skipped", "[drivers][bar]") {
  SECTION("polled") {
    CellSimProcess sim({"--bar-garbage-every", "2"});
    boost::asio::io_context io;
    auto config = sim.driversConfig().bar;
    config.poll_timeout_s = 0.2;
    BarReader bar(io, config);
    bar.connect();
    for (int i = 0; i < 8; ++i) CHECK(bar.read().kind == BarLineKind::kReading);
    CHECK(bar.stats().garbage_lines + bar.stats().partial_lines >= 2);
  }
  SECTION("streamed") {
    CellSimProcess sim({"--bar-mode", "streamed", "--stream-hz", "50", "--bar-garbage-every", "3"});
    boost::asio::io_context io;
    auto config = sim.driversConfig().bar;
    config.mode = "streamed";
    BarReader bar(io, config);
    bar.connect();
    for (int i = 0; i < 12; ++i) CHECK(bar.read().kind == BarLineKind::kReading);
    CHECK(bar.stats().garbage_lines >= 2);
  }
}

TEST_CASE("Bar: dropped lines are polled again", "[drivers][bar]") {
  CellSimProcess sim({"--bar-drop-every", "3"});
  boost::asio::io_context io;
  auto config = sim.driversConfig().bar;
  config.poll_timeout_s = 0.2;
  BarReader bar(io, config);
  bar.connect();
  for (int i = 0; i < 6; ++i) CHECK(bar.read().kind == BarLineKind::kReading);
  CHECK(bar.stats().timeouts >= 2);
}

TEST_CASE("Bar: readings that stop are stale within stale_after_s", "[drivers][bar]") {
  SECTION("streamed") {
    CellSimProcess sim({"--bar-mode", "streamed", "--stream-hz", "50"});
    boost::asio::io_context io;
    auto config = sim.driversConfig().bar;
    config.mode = "streamed";
    config.stale_after_s = 0.4;
    BarReader bar(io, config);
    bar.connect();
    CHECK(bar.read().kind == BarLineKind::kReading);
    REQUIRE(sim.control("fault stall bar 1.5").rfind("ok", 0) == 0);
    const auto t0 = Clock::now();
    CHECK_THROWS_AS(bar.read(), StaleReadingError);
    CHECK(bar.isStale());
    CHECK(Clock::now() - t0 < std::chrono::seconds(10));  // detected, not hung
    std::this_thread::sleep_for(std::chrono::milliseconds(1200));
    CHECK(bar.read().kind == BarLineKind::kReading);
    CHECK_FALSE(bar.isStale());
  }
  SECTION("polled") {
    CellSimProcess sim({"--bar-stall-after", "2", "--stall-s", "30"});
    boost::asio::io_context io;
    auto config = sim.driversConfig().bar;
    config.poll_timeout_s = 0.1;
    config.stale_after_s = 0.5;
    BarReader bar(io, config);
    bar.connect();
    bar.read();
    bar.read();
    try {
      bar.read();
      FAIL("no stale error");
    } catch (const StaleReadingError& e) {
      CHECK_THAT(e.what(), Catch::Contains("does not answer"));
    }
    CHECK(bar.stats().timeouts >= 3);
  }
}

TEST_CASE("Bar: no probe and device status lines", "[drivers][bar]") {
  CellSimProcess sim;
  boost::asio::io_context io;
  BarReader bar(io, sim.driversConfig().bar);
  bar.connect();
  REQUIRE(sim.control("fault noprobe").rfind("ok", 0) == 0);
  CHECK(bar.read().kind == BarLineKind::kNoProbe);
  CHECK_THROWS_AS(bar.readValueMm(), BarStatusError);
  REQUIRE(sim.control("fault noprobe off").rfind("ok", 0) == 0);
  CHECK(bar.read().kind == BarLineKind::kReading);
}

TEST_CASE("Bar: disconnect and reconnect", "[drivers][bar]") {
  CellSimProcess sim({"--bar-mode", "streamed", "--stream-hz", "50"});
  boost::asio::io_context io;
  auto config = sim.driversConfig().bar;
  config.mode = "streamed";
  BarReader bar(io, config);
  bar.connect();
  CHECK(bar.read().kind == BarLineKind::kReading);
  REQUIRE(sim.control("fault disconnect bar 0.5").rfind("ok", 0) == 0);
  CHECK_THROWS_AS(bar.read(), DisconnectedError);
  CHECK(bar.stats().disconnects == 1);
  bar.reconnect(10);
  CHECK(bar.read().kind == BarLineKind::kReading);
}

TEST_CASE("Bar: other line formats and units", "[drivers][bar]") {
  SECTION("mitutoyo, streamed, inches") {
    CellSimProcess sim(
        {"--bar-mode", "streamed", "--stream-hz", "50"},
        R"({"bar": {"format": "mitutoyo", "mode": "streamed", "unit_scale_mm": 25.4}})");
    REQUIRE(sim.control("connect B1C2 bar_mm=here").rfind("ok", 0) == 0);
    boost::asio::io_context io;
    BarReader bar(io, sim.driversConfig().bar);
    bar.connect();
    CHECK(std::abs(bar.readValueMm()) < 0.01);
  }
  SECTION("gn, polled with R") {
    CellSimProcess sim({}, R"({"bar": {"format": "gn", "poll_command": "R"}})");
    boost::asio::io_context io;
    BarReader bar(io, sim.driversConfig().bar);
    bar.connect();
    CHECK(bar.read().line.rfind("GN01,", 0) == 0);
  }
}

TEST_CASE(
    "Bar: a true robot with backlash reads its joints' last direction, and --realism ideal not",
    "[drivers][bar]") {
  // Joint 2 with 0.04 deg of backlash: its angle is 0.02 deg ahead of its reading in the direction
  // it last moved (cellsim starts as if every joint had moved up).
  const std::string realism = "{\"backlash_deg\": [0, 0.04, 0, 0, 0, 0]}";
  for (const bool ideal : {false, true}) {
    CAPTURE(ideal);
    CellSimProcess probe;  // for a private folder to hold the realism file
    const std::string path = probe.dir() + "/realism.json";
    REQUIRE(robocal::test::runShell("printf '%s' '" + realism + "' > " + path).first == 0);
    CellSimProcess sim({"--time-scale", "20", "--noise-mm", "0", "--realism",
                        ideal ? std::string("ideal") : path});
    REQUIRE(sim.control("connect B2C3 bar_mm=here").rfind("ok", 0) == 0);
    const auto config = sim.driversConfig();
    boost::asio::io_context io;
    BarReader bar(io, config.bar);
    bar.connect();
    CHECK(std::abs(bar.readValueMm()) < 0.005);
    ValController val(io, config.val);
    val.connect();
    val.moveJoints({0, 45.05, -90, 0, 45, 0});
    val.moveJoints(kStart);  // back to the same readings, joint 2 now moving down
    const auto model = robocal::loadModelFile(ROBOCAL_SOURCE_DIR "/config/puma560-paper.json");
    const double backlash_mm = trueLength(model, {0, 44.98, -90, 0, 45, 0}, 1, 2) -
                               trueLength(model, {0, 45.02, -90, 0, 45, 0}, 1, 2);
    REQUIRE(std::abs(backlash_mm) > 0.1);
    REQUIRE(std::abs(backlash_mm) < 1.0);
    CHECK(bar.readValueMm() == Approx(ideal ? 0.0 : backlash_mm).margin(0.005));
  }
}
