// The VAL II monitor's replies as the serial port delivers them: the reply collector (echo,
// prompt, error lines `*...*`), controller error classification and the WHERE parser.
// Documented errors: ProtocolError from parseWhere, the ControllerError family from throwError.
// Properties: every collected error message throws the ControllerError subtype its
// classification names; parsed WHERE joints are finite.
#include "fuzz_common.hpp"

#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/protocol.hpp>

using namespace robocal::drivers;
using robocal::fuzz::check;

namespace {

const ValDialect& dialect() {
  static const ValDialect d{ValConfig{}};
  return d;
}

void where(const std::vector<std::string>& lines) {
  try {
    const WhereReply r = parseWhere(lines, dialect().config());
    for (double v : r.joints_deg) check(std::isfinite(v), "WHERE joint is not finite");
    if (r.location)
      for (double v : *r.location) check(std::isfinite(v), "WHERE location is not finite");
  } catch (const ProtocolError&) {
  }
}

void error(const std::string& message) {
  const ValErrorKind kind = dialect().classify(message);
  try {
    dialect().throwError("WHERE", message);
  } catch (const ArmPowerOffError&) {
    check(kind == ValErrorKind::kPowerOff, "ArmPowerOffError for another kind", message);
  } catch (const OutOfRangeError&) {
    check(kind == ValErrorKind::kOutOfRange, "OutOfRangeError for another kind", message);
  } catch (const ControllerError& e) {
    check(kind == ValErrorKind::kOther, "plain ControllerError for a classified kind", message);
    check(e.controllerMessage() == message, "ControllerError lost the controller's message");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return robocal::fuzz::guarded(data, size, [](const std::string& bytes) {
    // As the driver sees it: the reply to WHERE, fed whole and then in small pieces.
    ValReplyCollector whole(dialect(), "WHERE");
    whole.feed(bytes);
    if (whole.complete()) where(whole.lines());
    for (const auto& m : whole.errors()) error(m);

    ValReplyCollector pieces(dialect(), "WHERE");
    const std::size_t step = bytes.empty() ? 1 : 1 + static_cast<unsigned char>(bytes[0]) % 7;
    for (std::size_t i = 0; i < bytes.size() && !pieces.complete(); i += step)
      pieces.feed(std::string_view(bytes).substr(i, step));
    for (const auto& m : pieces.errors()) error(m);

    // Every line, the echo and the prompt included: the WHERE parser must cope with any of them.
    LineSplitter splitter;
    std::vector<std::string> lines;
    splitter.feed(bytes, lines);
    lines.push_back(splitter.takePending());
    where(lines);
    for (const auto& l : lines)
      if (const auto m = dialect().errorMessage(l)) error(*m);
  });
}
