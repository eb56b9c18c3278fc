// The VAL II monitor's replies as the serial port delivers them, in each dialect preset (val2,
// vplus, kawasaki-as, chosen by the input's length): the reply collector (echo behind any prompt,
// error lines, ignored completion lines, questions), error classification by severity and the
// WHERE parser. Documented errors: ProtocolError from parseWhere, the ControllerError family
// from throwError. Properties: every collected error message throws the ControllerError subtype
// its classification names; the most severe error is at least as severe as every other; a
// reply ended by a question has no prompt; parsed WHERE joints are finite.
#include "fuzz_common.hpp"

#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/protocol.hpp>

using namespace robocal::drivers;
using robocal::fuzz::check;

namespace {

const ValDialect* current = nullptr;

const ValDialect& dialect() {
  return *current;
}

const ValDialect& presetFor(std::size_t size) {
  static const std::vector<ValDialect> all = [] {
    std::vector<ValDialect> out;
    for (const auto& name : valPresetNames()) out.emplace_back(valPreset(name));
    return out;
  }();
  return all[size % all.size()];
}

void severity(const std::vector<std::string>& errors) {
  if (errors.empty()) return;
  const ValErrorKind worst = dialect().classify(dialect().mostSevere(errors));
  for (const auto& m : errors)
    check(worst <= dialect().classify(m), "mostSevere missed a more severe error", m);
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
    current = &presetFor(bytes.size());
    // As the driver sees it: the reply to WHERE, fed whole and then in small pieces.
    ValReplyCollector whole(dialect(), "WHERE");
    whole.feed(bytes);
    whole.quiet();
    if (whole.complete()) where(whole.lines());
    for (const auto& m : whole.errors()) error(m);
    severity(whole.errors());
    if (!whole.question().empty())
      check(whole.prompt().empty() && dialect().isQuestion(whole.question()),
            "a question that is a prompt, or not a question", whole.question());

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
