// Lines from the ball-bar reader, classified by each preset dialect (mm_suffix, mitutoyo, gn,
// and mm_suffix with a range). BarDialect::parse throws nothing: every line is a reading or a
// status or garbage. Properties: a reading is finite and inside range_mm when one is set;
// unprintable lines are garbage; a reading printed the way the reader prints it (as the
// simulator does) parses back to the same value.
#include "fuzz_common.hpp"

#include <robocal/drivers/protocol.hpp>

#include <memory>

using namespace robocal::drivers;
using robocal::fuzz::check;

namespace {

const std::vector<std::unique_ptr<BarDialect>>& dialects() {
  static const auto all = [] {
    std::vector<std::unique_ptr<BarDialect>> out;
    for (const auto& format : barPresetNames()) {
      BarConfig c;
      c.format = format;
      out.push_back(std::make_unique<BarDialect>(c));
    }
    BarConfig ranged;
    ranged.range_mm = 2.0;
    out.push_back(std::make_unique<BarDialect>(ranged));
    return out;
  }();
  return all;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return robocal::fuzz::guarded(data, size, [](const std::string& bytes) {
    LineSplitter splitter;
    std::vector<std::string> lines;
    splitter.feed(bytes, lines);
    lines.push_back(splitter.takePending());
    for (const auto& line : lines) {
      for (const auto& d : dialects()) {
        const BarLine parsed = d->parse(line);
        if (!isPrintableText(line))
          check(parsed.kind == BarLineKind::kGarbage, "unprintable line not garbage", line);
        if (parsed.kind != BarLineKind::kReading) continue;
        const double v = parsed.value_mm;
        check(std::isfinite(v), "reading is not finite", line);
        const double range = d->config().range_mm;
        check(range <= 0 || std::abs(v) <= range, "reading outside range_mm", line);
        if (std::abs(v) > 1e6) continue;  // wider than the reader's fixed-width format
        const std::string printed = formatBarReading(d->config().format, v);
        const BarLine again = d->parse(printed);
        check(
            again.kind == BarLineKind::kReading && robocal::fuzz::close(again.value_mm, v, 1e-4, 0),
            "printed reading does not parse back", line + " -> " + printed);
      }
    }
  });
}
