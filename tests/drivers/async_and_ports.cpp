// The asynchronous API as the daemon's event loop uses it, the motion monitor, and how ports are
// opened (libserialport refuses ptys; exclusive opens) - all over real ptys against cellsim.
#include "cellsim_process.hpp"

#include <robocal/drivers/bar.hpp>
#include <robocal/drivers/val.hpp>

#include <catch2/catch.hpp>

using namespace robocal::drivers;
using robocal::test::CellSimProcess;

TEST_CASE("Async: one event loop drives the controller and the streaming bar", "[drivers][async]") {
  CellSimProcess sim({"--time-scale", "20", "--bar-mode", "streamed", "--stream-hz", "50"});
  REQUIRE(sim.control("connect B1C1 bar_mm=here").rfind("ok", 0) == 0);
  auto config = sim.driversConfig();
  config.bar.mode = "streamed";
  boost::asio::io_context io;
  ValController val(io, config.val);
  BarReader bar(io, config.bar);
  val.connect();
  bar.connect();

  int bar_lines = 0, progress = 0;
  bar.onLine([&](const BarReading&) { ++bar_lines; });
  std::string unsolicited;
  val.onUnsolicitedError([&](const std::string& m) { unsolicited = m; });

  bool moved = false;
  std::exception_ptr error;
  const Joints6 target{0.2, 45.1, -90, 0, 45, 0};
  val.asyncMoveJoints(
      target,
      [&](std::exception_ptr e, WhereReply w) {
        error = e;
        moved = true;
        if (!e) CHECK(std::abs(w.joints_deg[0] - 0.2) < 0.006);
      },
      [&](const WhereReply&) { ++progress; });
  REQUIRE(runIoUntil(
      io, [&] { return moved; }, deadlineAfter(20)));
  CHECK_FALSE(error);
  CHECK(progress >= 2);
  CHECK(bar_lines >= 1);  // the bar streamed while the loop waited for the motion

  // An E-stop while nothing is asked is seen as it arrives.
  REQUIRE(sim.control("estop") == "ok estop");
  CHECK(runIoUntil(
      io, [&] { return !unsolicited.empty(); }, deadlineAfter(10)));
  CHECK_THAT(unsolicited, Catch::Contains("power off"));

  bool answered = false;
  val.asyncWhere([&](std::exception_ptr e, WhereReply) {
    error = e;
    answered = true;
  });
  REQUIRE(runIoUntil(
      io, [&] { return answered; }, deadlineAfter(10)));
  CHECK_THROWS_AS(std::rethrow_exception(error), ArmPowerOffError);  // reported once
  CHECK(std::abs(val.where().joints_deg[0] - 0.2) < 0.006);
}

TEST_CASE("MotionMonitor: arrived, stopped short, timed out", "[drivers][val]") {
  ValConfig c;
  c.still_polls = 2;
  c.stopped_short_s = 1;
  c.motion_timeout_s = 10;
  const Joints6 target{10, 0, 0, 0, 0, 0};
  const auto t0 = Clock::now();
  const auto at = [&](double s) { return t0 + std::chrono::milliseconds(int(s * 1000)); };
  using S = MotionMonitor::State;
  {
    MotionMonitor m(c, target, t0);
    CHECK(m.update({0, 0, 0, 0, 0, 0}, at(0.1)) == S::kMoving);
    CHECK(m.update({5, 0, 0, 0, 0, 0}, at(0.2)) == S::kMoving);
    CHECK(m.update({10, 0, 0, 0, 0, 0}, at(0.3)) == S::kMoving);
    CHECK(m.update({10, 0, 0, 0, 0, 0}, at(0.4)) == S::kMoving);
    CHECK(m.update({10.001, 0, 0, 0, 0, 0}, at(0.5)) == S::kArrived);
  }
  {
    MotionMonitor m(c, target, t0);
    CHECK(m.update({4, 0, 0, 0, 0, 0}, at(0.1)) == S::kMoving);
    CHECK(m.update({4, 0, 0, 0, 0, 0}, at(0.5)) == S::kMoving);
    CHECK(m.update({4, 0, 0, 0, 0, 0}, at(0.9)) == S::kMoving);
    CHECK(m.update({4, 0, 0, 0, 0, 0}, at(1.2)) == S::kStoppedShort);
    CHECK_THAT(m.explain(S::kStoppedShort, {4, 0, 0, 0, 0, 0}), Catch::Contains("6.000 deg off"));
  }
  {
    MotionMonitor m(c, target, t0);
    CHECK(m.update({1, 0, 0, 0, 0, 0}, at(9)) == S::kMoving);
    CHECK(m.update({2, 0, 0, 0, 0, 0}, at(11)) == S::kTimedOut);
  }
}

TEST_CASE("Ports: libserialport refuses a pty, opens are exclusive", "[drivers][transport]") {
  CellSimProcess sim;
  boost::asio::io_context io;
  SECTION("libserialport on a pty") {
    auto config = sim.driversConfig().val.serial;
    config.opener = "libserialport";
    SerialLink link(io, config);
    try {
      link.open();
      FAIL("libserialport opened a pty");
    } catch (const PortError& e) {
      CHECK_THAT(e.what(), Catch::Contains("termios"));
    }
  }
  SECTION("auto opens a pty link with termios") {
    SerialLink link(io, sim.driversConfig().val.serial);
    link.open();
    CHECK(link.opener() == "termios");
    CHECK(isPseudoTerminal(link.path()));
  }
  SECTION("a second program cannot take the port") {
    SerialLink first(io, sim.driversConfig().bar.serial);
    first.open();
    SerialLink second(io, sim.driversConfig().bar.serial);
    try {
      second.open();
      FAIL("opened twice");
    } catch (const PortError& e) {
      CHECK_THAT(e.what(), Catch::Contains("in use"));
    }
    first.close();
    CHECK_NOTHROW(second.open());
  }
}

TEST_CASE("Ports: an adapter is found by USB serial number or description",
          "[drivers][transport]") {
  std::vector<PortInfo> ports(3);
  ports[0].path = "/dev/ttyUSB0";
  ports[0].description = "FT232R USB UART - A10KXYZ1";
  ports[0].usb_serial = "A10KXYZ1";
  ports[0].usb_manufacturer = "FTDI";
  ports[1].path = "/dev/ttyUSB1";
  ports[1].description = "USB-Serial Controller";
  ports[1].usb_product = "USB-Serial Controller";
  ports[1].usb_manufacturer = "Prolific Technology Inc.";
  ports[2].path = "/dev/ttyUSB2";
  ports[2].description = "FT232R USB UART - B20QQQ";
  ports[2].usb_serial = "B20QQQ";
  ports[2].usb_manufacturer = "FTDI";
  SerialConfig c;
  c.usb_serial = "B20QQQ";
  CHECK(matchPort(ports, c) == "/dev/ttyUSB2");
  c.usb_serial.clear();
  c.usb_description = "prolific";
  CHECK(matchPort(ports, c) == "/dev/ttyUSB1");
  c.usb_description = "FTDI";
  try {
    matchPort(ports, c);
    FAIL("two FTDI adapters matched one name");
  } catch (const PortError& e) {
    CHECK_THAT(e.what(), Catch::Contains("more than one") && Catch::Contains("/dev/ttyUSB2"));
  }
  c.usb_serial = "A10KXYZ1";
  CHECK(matchPort(ports, c) == "/dev/ttyUSB0");
  c.usb_serial = "GONE";
  CHECK_THROWS_WITH(matchPort(ports, c), Catch::Contains("is the adapter plugged in"));
}
