// What a technician needs when wiring a cell: open a port, talk to the device, and say in plain
// words what is wrong (no port, no answer, garbled answer = wrong baud, unparseable answer).
// Used by `robocal probe`; the daemon can run the same checks.
#pragma once

#include <robocal/drivers/bar.hpp>
#include <robocal/drivers/val.hpp>

#include <functional>
#include <optional>
#include <string>

namespace robocal::drivers {

enum class Verdict {
  kOk,
  kNoPort,       // missing, unplugged, in use, no permission
  kNoAnswer,     // the port opens but nothing comes back
  kGarbled,      // bytes come back but not text: baud rate / parity / adapter
  kUnparseable,  // text comes back but not in the configured dialect
  kDeviceError,  // the device answers with an error (arm power off, no probe, ...)
  kQuestion,     // the controller asks something ("Initialize?"): the operator answers it
};
const char* verdictName(Verdict v);

struct Diagnosis {
  Verdict verdict = Verdict::kOk;
  std::string message;   // one paragraph, technician words
  std::string received;  // what came back (escaped), when it helps
  std::optional<WhereReply> where;
  std::optional<BarReading> reading;
};

// Opens the controller's port, wakes the monitor, and reads WHERE.
Diagnosis diagnoseVal(boost::asio::io_context& io, const ValConfig& config);
// Opens the reader's port and takes readings for listen_s seconds (at least one), passing each
// to `on_reading`.
Diagnosis diagnoseBar(boost::asio::io_context& io, const BarConfig& config, double listen_s,
                      const std::function<void(const BarReading&)>& on_reading = {});

}  // namespace robocal::drivers
