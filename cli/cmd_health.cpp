// robocal health: the verdict of a health check (docs/health-check.md): do the check's samples
// still fit the calibrated model in use? Prints PASS, WARN or FAIL, the RMS against the
// reference, and what moved; the exit status says the verdict.
#include "args.hpp"

#include <robocal/formats/health_report.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/formats/samples_csv.hpp>
#include <robocal/solver/health.hpp>

#include <cstdio>
#include <nlohmann/json.hpp>

namespace robocal::cli {
namespace {

constexpr const char* kHelp =
    R"(usage: robocal health --model ACTIVE check-samples.csv [more.csv ...] [--json] [options]

Judges whether the calibrated model in use still fits the robot, from the samples of a health
check (robocal plan --check; docs/health-check.md). The samples are predicted by the model
without refitting; a small prior-weighted refit from the model names what moved, e.g.
"J2.offset +0.0500 deg", judged at the reference level or at the check's own noise when its
readings are noisier (a noisier day is not a change). Anything named: FAIL. Nothing named: the
RMS over the reference gives PASS below --warn-ratio, WARN from it, FAIL from --fail-ratio.
The reference is --baseline-mm when given (the RMS of the same check right after the
calibration), else the RMS the model's own fit reached (its provenance), else --fallback-mm.

  --model FILE         the calibrated model in use (model format)                 required
  --json               one JSON object instead of text
  --baseline-mm R      reference RMS: a check run right after the calibration
  --fallback-mm R      reference RMS when the model has no provenance              [0.084]
  --warn-ratio K       WARN from this RMS ratio when nothing is named              [2.5]
  --fail-ratio K       FAIL from this RMS ratio when nothing is named              [3]
  --significance Z     name a parameter when it explains Z sigma of the residuals  [3.5]

exit status: 0 PASS, 4 WARN, 5 FAIL, 1 an unreadable input, 2 a usage error
)";

int run(const std::vector<std::string>& argv) {
  const Args args(
      argv, {"model", "baseline-mm", "fallback-mm", "warn-ratio", "fail-ratio", "significance"},
      {"json", "help"});
  if (args.flag("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  HealthOptions options;
  if (args.has("baseline-mm")) options.baseline_rms_mm = args.number("baseline-mm", 0);
  options.fallback_rms_mm = args.number("fallback-mm", options.fallback_rms_mm);
  options.warn_ratio = args.number("warn-ratio", options.warn_ratio);
  options.fail_ratio = args.number("fail-ratio", options.fail_ratio);
  options.significance = args.number("significance", options.significance);
  if ((options.baseline_rms_mm && !(*options.baseline_rms_mm > 0)) ||
      !(options.fallback_rms_mm > 0))
    throw UsageError("--baseline-mm and --fallback-mm must be positive");
  if (!(options.warn_ratio > 0) || !(options.fail_ratio >= options.warn_ratio))
    throw UsageError("--warn-ratio must be positive and --fail-ratio at least --warn-ratio");
  if (!(options.significance > 0)) throw UsageError("--significance must be positive");

  const Model active = loadModelFile(args.required("model"));
  if (args.positional().empty()) throw UsageError("no check samples file given");
  std::vector<Sample> samples;
  for (const std::string& path : args.positional()) {
    auto more = loadSamplesFile(path);
    samples.insert(samples.end(), more.begin(), more.end());
  }
  if (samples.empty()) throw UsageError("the samples files hold no samples");

  const HealthVerdict verdict = assessHealth(active, samples, options);
  if (args.flag("json"))
    std::printf("%s\n", healthVerdictJson(verdict).dump().c_str());
  else
    std::fputs(healthVerdictText(verdict).c_str(), stdout);
  return healthExitStatus(verdict.status);
}

const RegisterCommand registered(
    {"health", "judge a health check's samples against the calibrated model (pass/warn/fail)",
     run});

}  // namespace
}  // namespace robocal::cli
