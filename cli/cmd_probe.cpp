// robocal probe: what a technician runs when wiring a cell. Opens the controller's and/or the
// ball-bar reader's port, shows WHERE and live bar readings, and says in plain words what is
// wrong: no port, no answer, wrong baud rate (garbled answer), or an answer robocal cannot read.
#include "args.hpp"

#include <robocal/build_info.hpp>
#include <robocal/drivers/config.hpp>
#include <robocal/drivers/diagnose.hpp>

#include <unistd.h>

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
)";

void applyPort(drivers::SerialConfig& serial, const std::string& port) {
  serial.path.clear();
  serial.usb_serial.clear();
  serial.usb_description.clear();
  if (port.rfind("usb-serial:", 0) == 0)
    serial.usb_serial = port.substr(11);
  else if (port.rfind("usb:", 0) == 0)
    serial.usb_description = port.substr(4);
  else
    serial.path = port;
}

void report(const drivers::Diagnosis& d) {
  if (d.verdict == drivers::Verdict::kOk) {
    std::printf("  OK: %s\n", d.message.c_str());
  } else {
    std::printf("  PROBLEM (%s): %s\n", drivers::verdictName(d.verdict), d.message.c_str());
    if (!d.received.empty()) std::printf("  received: %s\n", d.received.c_str());
  }
}

int run(const std::vector<std::string>& argv) {
  const Args args(
      argv, {"val", "bar", "config", "val-baud", "bar-baud", "bar-mode", "bar-format", "seconds"},
      {"help"});
  if (args.flag("help")) {
    std::printf(kHelp, build::kDaemonConfigFile);
    return 0;
  }
  std::string config_file = args.get("config", "");
  if (config_file.empty())
    for (const char* fallback : {"config/drivers.json", build::kDaemonConfigFile})
      if (config_file.empty() && ::access(fallback, R_OK) == 0) config_file = fallback;
  drivers::DriversConfig config;
  if (!config_file.empty()) config = drivers::loadDriversOrDaemonConfig(config_file);
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
      std::printf("  joints (deg):");
      for (double v : d.where->joints_deg) std::printf(" %9.3f", v);
      std::printf("\n");
      if (d.where->location) {
        std::printf("  X Y Z (mm), O A T (deg):");
        for (double v : *d.where->location) std::printf(" %9.3f", v);
        std::printf("\n");
      }
    }
    report(d);
    ok = ok && d.verdict == drivers::Verdict::kOk;
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
