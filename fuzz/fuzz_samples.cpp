// The samples file (docs/samples-format.md): CSV with a header row. parseSamples returns the
// samples or throws FormatError. Property: the samples written back (formatSamples) parse to the
// same samples, the values equal to the writer's decimals; checked when the values are of
// plausible size (|value| < 1e6 and a length >= 0.001 mm: the writer prints fixed decimals).
#include "fuzz_common.hpp"

#include <robocal/formats/samples_csv.hpp>

using namespace robocal;
using robocal::fuzz::check;
using robocal::fuzz::close;

namespace {

bool plausible(const Sample& s) {
  bool ok = std::abs(s.extension_mm) < 1e6 && std::abs(s.lat_deg) < 1e6 &&
            std::abs(s.lon_deg) < 1e6 && s.length_mm >= 1e-3 && s.length_mm < 1e6;
  for (int j = 0; j < kJointCount; ++j) ok = ok && std::abs(s.joints_deg[j]) < 1e6;
  return ok;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return robocal::fuzz::guarded(data, size, [](const std::string& text) {
    std::vector<Sample> samples;
    try {
      samples = parseSamples(text, "fuzz.csv");
    } catch (const FormatError&) {
      return;
    }
    for (const Sample& s : samples) {
      check(s.ball_index >= 0 && s.ball_index < kBallCount, "ball out of range");
      check(s.chuck_index >= 0 && s.chuck_index < kChuckCount, "chuck out of range");
      check(s.length_mm > 0 && std::isfinite(s.length_mm), "length not positive and finite");
      if (!plausible(s)) return;
    }
    const std::string written = formatSamples(samples);
    std::vector<Sample> again;
    try {
      again = parseSamples(written, "written");
    } catch (const FormatError& e) {
      robocal::fuzz::fail("written samples do not parse", e.what());
    }
    check(again.size() == samples.size(), "sample count changed on a round trip");
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const Sample &a = samples[i], &b = again[i];
      bool same =
          a.shell == b.shell && a.ball_index == b.ball_index && a.chuck_index == b.chuck_index &&
          close(a.extension_mm, b.extension_mm, 6e-4, 0) && close(a.lat_deg, b.lat_deg, 6e-5, 0) &&
          close(a.lon_deg, b.lon_deg, 6e-5, 0) && close(a.length_mm, b.length_mm, 6e-7, 0) &&
          a.time_s.has_value() == b.time_s.has_value() &&
          (!a.time_s || close(*a.time_s, *b.time_s, 6e-4, 0));
      for (int j = 0; j < kJointCount; ++j)
        same = same && close(a.joints_deg[j], b.joints_deg[j], 6e-7, 0);
      check(same, "sample changed on a round trip", formatSampleRow(a));
    }
  });
}
