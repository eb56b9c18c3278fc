// robocal probe: what a technician runs when wiring a cell. Opens the controller's and/or the
// ball-bar reader's port, shows WHERE and live bar readings, and says in plain words what is
// wrong: no port, no answer, wrong baud rate (garbled answer), or an answer robocal cannot read.
#include "args.hpp"
#include "device_args.hpp"

#include <robocal/build_info.hpp>
#include <robocal/drivers/config.hpp>
#include <robocal/drivers/diagnose.hpp>
#include <robocal/drivers/move_test.hpp>
#include <robocal/formats/model_json.hpp>

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace robocal::cli {
namespace {

constexpr const char* kHelp = R"(usage: robocal probe [--val PORT] [--bar PORT] [options]

Checks the serial link to the VAL II controller (--val) and/or the ball-bar reader (--bar):
opens the port, talks to the device, shows WHERE and a few seconds of live bar readings, and
explains what is wrong if something is. Exit code 0 when every device probed answers properly.

PORT is a device path (/dev/ttyUSB0, /dev/serial/by-id/..., a pty), "usb-serial:NUMBER" or
"usb:TEXT" (an adapter's USB serial number or a part of its description; see robocal ports).
Without --val/--bar, the ports of the config file are probed.

The config file is a drivers config (config/drivers.json) or robocald's own config file, whose
"drivers" section is read as the daemon reads it. Without --config: config/drivers.json if
present, else the daemon's %s if present, else the defaults.

  --config FILE         drivers or robocald config (ports, dialects, baud rates)
  --val-baud N          override val.serial.baud
  --bar-baud N          override bar.serial.baud
  --bar-mode M          override bar.mode (polled or streamed)
  --bar-format F        override bar.format (mm_suffix, mitutoyo, gn)
  --seconds S           how long to show live bar readings              [3]

Bring-up move test (moves the arm; the controller only):
  --move-test DEG       after WHERE: SPEED 10, then each joint in turn by +DEG and back (-DEG
                        near a limit), WHERE polled during every move; prints what the
                        controller did, the round-trip times and whether the dialect works.
                        DEG is 0.1 to 10.
  --model FILE          joint limits to respect in the move test (a model file)
  --i-have-cleared-the-cell   required with --move-test: the arm will move. Clear the cell,
                        detach the ball-bar, keep a hand on the E-stop.
)";

void report(const drivers::Diagnosis& d) {
  if (d.verdict == drivers::Verdict::kOk) {
    std::printf("  OK: %s\n", d.message.c_str());
  } else {
    std::printf("  PROBLEM (%s): %s\n", drivers::verdictName(d.verdict), d.message.c_str());
    if (!d.received.empty()) std::printf("  received: %s\n", d.received.c_str());
  }
}

void printJoints(const char* label, const drivers::Joints6& joints_deg) {
  std::printf("%s", label);
  for (double v : joints_deg) std::printf(" %9.3f", v);
  std::printf("\n");
}

// The move test: each joint out and back, and what was seen. True when the dialect works.
bool moveTest(boost::asio::io_context& io, const drivers::ValConfig& config,
              const drivers::MoveTestOptions& options) {
  std::printf("Move test: SPEED %.0f, each joint by %.3f deg and back\n", options.speed_percent,
              options.step_deg);
  std::fflush(stdout);
  drivers::ValController val(io, config);
  try {
    val.connect();
  } catch (const drivers::DriverError& e) {
    std::printf("  PROBLEM: %s\n", e.what());
    return false;
  }
  const drivers::MoveTestReport r = drivers::runMoveTest(val, options, [](const std::string& s) {
    std::printf("  %s\n", s.c_str());
    std::fflush(stdout);
  });
  printJoints("  start joints (deg):", r.start_deg);
  if (!r.where_round_trip_s.empty()) {
    std::vector<double> t = r.where_round_trip_s;
    std::sort(t.begin(), t.end());
    std::printf("  WHERE round trip: median %.1f ms, max %.1f ms (%zu)\n", 1000 * t[t.size() / 2],
                1000 * t.back(), t.size());
  }
  std::printf("  %s: %s\n", r.ok ? "OK" : "PROBLEM", r.verdict.c_str());
  return r.ok;
}

int run(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"val", "bar", "config", "val-baud", "bar-baud", "bar-mode", "bar-format",
                   "seconds", "move-test", "model"},
                  {"help", "i-have-cleared-the-cell"});
  if (args.flag("help")) {
    std::printf(kHelp, build::kDaemonConfigFile);
    return 0;
  }
  const std::string config_file = findDriversConfig(args.get("config", ""));
  drivers::DriversConfig config = loadDevicesConfig(config_file);
  std::printf("Drivers config: %s\n", config_file.empty() ? "defaults" : config_file.c_str());
  bool do_val = args.has("val"), do_bar = args.has("bar");
  if (!do_val && !do_bar) do_val = do_bar = true;
  if (args.has("val")) applyPort(config.val.serial, args.get("val", ""));
  if (args.has("bar")) applyPort(config.bar.serial, args.get("bar", ""));
  config.val.serial.baud = static_cast<int>(args.integer("val-baud", config.val.serial.baud));
  config.bar.serial.baud = static_cast<int>(args.integer("bar-baud", config.bar.serial.baud));
  config.bar.mode = args.get("bar-mode", config.bar.mode);
  config.bar.format = args.get("bar-format", config.bar.format);
  const double seconds = args.number("seconds", 3);
  if (seconds < 0 || seconds > 3600) throw UsageError("--seconds must be 0 to 3600");
  drivers::MoveTestOptions move_test;
  const bool do_move_test = args.has("move-test");
  if (do_move_test) {
    move_test.step_deg = args.number("move-test", 2);
    if (!(move_test.step_deg >= 0.1 && move_test.step_deg <= 10))
      throw UsageError("--move-test: DEG must be 0.1 to 10 (a small move per joint)");
    if (!args.flag("i-have-cleared-the-cell"))
      throw UsageError(
          "--move-test moves the arm: every joint in turn by " +
          drivers::formatFixed(move_test.step_deg, 3) +
          " deg and back at SPEED 10. Clear the cell, detach the ball-bar, keep a hand on the "
          "E-stop, then add --i-have-cleared-the-cell. Nothing was sent to the controller.");
    if (args.has("bar")) throw UsageError("--move-test is for the controller only: drop --bar");
    do_bar = false;
    do_val = true;
    if (args.has("model")) {
      const Model model = loadModelFile(args.get("model", ""));
      for (int k = 0; k < 6; ++k) {
        move_test.min_deg[k] = model.joints[k].min_deg;
        move_test.max_deg[k] = model.joints[k].max_deg;
      }
    }
  }
  try {
    drivers::validate(config.val);
    drivers::validate(config.bar);
  } catch (const drivers::ConfigError& e) {
    throw UsageError(e.what());
  }

  bool ok = true;
  boost::asio::io_context io;
  if (do_val) {
    const auto& s = config.val.serial;
    std::printf("VAL II controller on %s\n", !s.path.empty() ? s.path.c_str()
                                             : !s.usb_serial.empty()
                                                 ? ("USB serial " + s.usb_serial).c_str()
                                                 : ("USB \"" + s.usb_description + "\"").c_str());
    std::fflush(stdout);
    const drivers::Diagnosis d = drivers::diagnoseVal(io, config.val);
    if (d.where) {
      printJoints("  joints (deg):", d.where->joints_deg);
      if (d.where->location) printJoints("  X Y Z (mm), O A T (deg):", *d.where->location);
    }
    report(d);
    ok = ok && d.verdict == drivers::Verdict::kOk;
    // The arm moves only after the link and the dialect answered properly.
    if (do_move_test) ok = ok && moveTest(io, config.val, move_test);
  }
  if (do_bar) {
    const auto& s = config.bar.serial;
    std::printf("Ball-bar reader on %s\n", !s.path.empty() ? s.path.c_str()
                                           : !s.usb_serial.empty()
                                               ? ("USB serial " + s.usb_serial).c_str()
                                               : ("USB \"" + s.usb_description + "\"").c_str());
    std::fflush(stdout);
    drivers::Clock::time_point t0{};
    const drivers::Diagnosis d =
        drivers::diagnoseBar(io, config.bar, seconds, [&](const drivers::BarReading& r) {
          if (t0 == drivers::Clock::time_point{}) t0 = r.time;
          const double t = std::chrono::duration<double>(r.time - t0).count();
          if (r.kind == drivers::BarLineKind::kReading)
            std::printf("  %7.2f s  %+10.5f mm   (\"%s\")\n", t, r.value_mm, r.line.c_str());
          else
            std::printf("  %7.2f s  %s   (\"%s\")\n", t, drivers::barLineKindName(r.kind),
                        r.line.c_str());
          std::fflush(stdout);
          // Polled readers: about four readings a second is enough to watch.
          if (config.bar.mode == "polled") ::usleep(250000);
        });
    report(d);
    ok = ok && d.verdict == drivers::Verdict::kOk;
  }
  return ok ? 0 : 1;
}

const RegisterCommand registered(
    {"probe", "check the serial links to the controller and the ball-bar reader", run});

}  // namespace
}  // namespace robocal::cli
