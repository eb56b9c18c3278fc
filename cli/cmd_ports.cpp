// robocal ports: the machine's serial ports with their USB details (libserialport enumeration),
// and the config lines that name each adapter so that it is found again after re-plugging.
#include "args.hpp"

#include <robocal/drivers/transport.hpp>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>

namespace robocal::cli {
namespace {

constexpr const char* kHelp = R"(usage: robocal ports [--json]

Lists the serial ports of this machine (USB-serial adapters appear as /dev/ttyUSB* or
/dev/ttyACM*), with their USB vendor/product, description and serial number. Name an adapter in
config/drivers.json by its serial number ("usb_serial") or description ("usb_description") so it
is found again when it comes back as another /dev/ttyUSB number. Note: listing may briefly open
built-in ports (/dev/ttyS*) to see whether they exist.

  --json    one JSON array instead of the table
)";

// /dev/serial/by-id and by-path links that point at `path`.
std::vector<std::string> stableLinks(const std::string& path) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const char* dir : {"/dev/serial/by-id", "/dev/serial/by-path"}) {
    for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
      std::error_code ec2;
      if (std::filesystem::canonical(entry.path(), ec2) == std::filesystem::path(path))
        out.push_back(entry.path().string());
    }
  }
  return out;
}

int run(const std::vector<std::string>& argv) {
  const Args args(argv, {}, {"help", "json"});
  if (args.flag("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  const auto ports = drivers::listSerialPorts();
  if (args.flag("json")) {
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (const auto& p : ports) {
      nlohmann::ordered_json j{
          {"path", p.path}, {"description", p.description}, {"transport", p.transport}};
      if (p.transport == "usb") {
        j["usb_vid"] = p.usb_vid;
        j["usb_pid"] = p.usb_pid;
        j["usb_manufacturer"] = p.usb_manufacturer;
        j["usb_product"] = p.usb_product;
        j["usb_serial"] = p.usb_serial;
        j["usb_bus"] = p.usb_bus;
        j["usb_address"] = p.usb_address;
      }
      j["links"] = stableLinks(p.path);
      list.push_back(j);
    }
    std::printf("%s\n", list.dump(2).c_str());
    return 0;
  }
  if (ports.empty()) {
    std::printf(
        "No serial ports found. Plug in the USB-serial adapter (it appears as "
        "/dev/ttyUSB* or /dev/ttyACM*) and run this again.\n");
    return 0;
  }
  for (const auto& p : ports) {
    std::printf("%-14s %-9s %s\n", p.path.c_str(), p.transport.c_str(), p.description.c_str());
    if (p.transport == "usb") {
      std::printf("    USB %04x:%04x  %s %s  serial number %s  bus %d address %d\n",
                  p.usb_vid & 0xffff, p.usb_pid & 0xffff, p.usb_manufacturer.c_str(),
                  p.usb_product.c_str(), p.usb_serial.empty() ? "(none)" : p.usb_serial.c_str(),
                  p.usb_bus, p.usb_address);
      if (!p.usb_serial.empty())
        std::printf("    in drivers.json: \"serial\": {\"usb_serial\": \"%s\"}\n",
                    p.usb_serial.c_str());
      else
        std::printf(
            "    no serial number: name it by \"usb_description\" or a /dev/serial/by-path "
            "link\n");
    }
    for (const auto& l : stableLinks(p.path)) std::printf("    link %s\n", l.c_str());
  }
  return 0;
}

const RegisterCommand registered({"ports", "list serial ports with their USB details", run});

}  // namespace
}  // namespace robocal::cli
