#include "device_args.hpp"

#include <robocal/build_info.hpp>

#include <unistd.h>

namespace robocal::cli {

std::string findDriversConfig(const std::string& given) {
  if (!given.empty()) return given;
  for (const char* fallback : {"config/drivers.json", build::kDaemonConfigFile})
    if (::access(fallback, R_OK) == 0) return fallback;
  return "";
}

drivers::DriversConfig loadDevicesConfig(const std::string& path) {
  return path.empty() ? drivers::DriversConfig{} : drivers::loadDriversOrDaemonConfig(path);
}

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

}  // namespace robocal::cli
