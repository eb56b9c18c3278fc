// robocald's client protocol: one request line as a client sends it (docs/protocol.md).
// parseRequest returns a Request or throws RequestError. Properties: a parsed request has a known
// command and a finite nudge; a RequestError's message frames to exactly one wire line (the
// daemon sends it back to the client).
#include "fuzz_common.hpp"

#include <robocal/proto/protocol.hpp>

using namespace robocal::proto;
using robocal::fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return robocal::fuzz::guarded(data, size, [](const std::string& line) {
    try {
      const Request req = parseRequest(line);
      check(std::string(cmdName(req.cmd)) != "?", "parsed request with an unknown command");
      check(std::isfinite(req.nudge_mm), "parsed nudge is not finite");
      const std::string ack = frame(ackObject(req.cmd, req.reason));
      check(ack.find('\n') == ack.size() - 1, "ACK is not one line", ack);
    } catch (const RequestError& e) {
      const std::string wire = frame(errorObject(e.what(), e.cmd()));
      check(!wire.empty() && wire.find('\n') == wire.size() - 1, "ERROR is not one line", wire);
      check(nlohmann::json::accept(wire), "ERROR line is not valid JSON", wire);
    }
  });
}
