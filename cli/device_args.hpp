// The options `robocal probe` and `robocal term` share for reaching the devices: which drivers
// config to read, and a port given on the command line.
#pragma once

#include <robocal/drivers/config.hpp>

#include <string>

namespace robocal::cli {

// `given` (--config), else config/drivers.json if present, else the daemon's installed config
// file if present, else "" (the defaults).
std::string findDriversConfig(const std::string& given);
// The drivers config of that file (a drivers or robocald config), or the defaults for "".
drivers::DriversConfig loadDevicesConfig(const std::string& path);

// A port as the user writes it: a device path, "usb-serial:NUMBER" or "usb:TEXT" (an adapter's
// USB serial number or part of its description).
void applyPort(drivers::SerialConfig& serial, const std::string& port);

}  // namespace robocal::cli
