// robocal iso-plan and iso-report: an ISO 9283-style performance test with the ball-bar
// (planner/iso_plan.hpp, solver/iso9283.hpp, formats/iso_report.hpp; docs/iso9283.md). robocald
// runs the plan like any other and writes the report at its end; iso-report computes it offline
// from a samples file.
#include "args.hpp"

#include <robocal/formats/error.hpp>
#include <robocal/formats/iso_report.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/formats/samples_csv.hpp>
#include <robocal/planner/cell_json.hpp>
#include <robocal/planner/check.hpp>
#include <robocal/planner/iso_plan.hpp>
#include <robocal/planner/plan_json.hpp>

#include <cstdio>

namespace robocal::cli {
namespace {

constexpr const char* kPlanHelp =
    R"(usage: robocal iso-plan --model M --cell C [--out iso.json] [--cycles N]
                        [--warmup-cycles N] [--spread-deg D]

Plans an ISO 9283-style test with the ball-bar (docs/iso9283.md): the cell's first connection
at its first extension, five poses on its shell (P1 nearest the centre of the cell's
work_volume, P2-P5 the corners of a square of --spread-deg about it), visited P1..P5 for the
warm-up cycles and then the measured cycles, each pose reached the same way every cycle. Start
it with robocald like a calibration (robocal start FILE): at its end robocald writes
iso9283.json and iso9283.txt in the run folder instead of fitting.

  --model FILE         the model the robot is commanded with                     required
  --cell FILE          the cell (docs/cell-format.md)                            required
  --out FILE           plan to write                                             [iso.json]
  --cycles N           measured cycles, 2 to 1000                                [30]
  --warmup-cycles N    cycles before them, left out of the figures               [3]
  --spread-deg D       P2-P5 this far from P1 in latitude and longitude, 2-40    [15]

exit status: 0 written, 1 an unreadable file or no safe test poses, 2 a usage error
)";

constexpr const char* kReportHelp =
    R"(usage: robocal iso-report --model M SAMPLES.csv [--warmup-cycles N] [--plan PLAN] [--json]

The figures of an ISO 9283-style test from its samples (docs/iso9283.md), along the bar: distance
accuracy AD and repeatability RD at each pose and between P1 and each other pose, and the drift
of P1 over the test, each with its 95 % interval; then what a ball-bar cannot give.

  --model FILE         the model the robot was commanded with                    required
  --plan FILE          the test's plan: its warm-up cycles and settings
  --warmup-cycles N    cycles of each pose left out             [the plan's, else 3]
  --json               the report as one JSON object (class "ISO9283")

exit status: 0, 1 an unreadable file or samples that are not such a test, 2 a usage error
)";

int wholeArg(const Args& args, const char* key, int fallback, int lo, int hi) {
  const long v = args.integer(key, fallback);
  if (v < lo || v > hi)
    throw UsageError(std::string("--") + key + " must be from " + std::to_string(lo) + " to " +
                     std::to_string(hi));
  return static_cast<int>(v);
}

int plan(const std::vector<std::string>& argv) {
  const Args args(argv, {"model", "cell", "out", "cycles", "warmup-cycles", "spread-deg"},
                  {"help"});
  if (args.flag("help")) {
    std::fputs(kPlanHelp, stdout);
    return 0;
  }
  const Model model = loadModelFile(args.required("model"));
  const CellConfig cell = loadCellFile(args.required("cell"));
  IsoTestSettings t;
  t.cycles = wholeArg(args, "cycles", t.cycles, 2, 1000);
  t.warmup_cycles = wholeArg(args, "warmup-cycles", t.warmup_cycles, 0, 1000);
  t.spread_deg = args.number("spread-deg", t.spread_deg);
  if (!(t.spread_deg >= 2 && t.spread_deg <= 40))
    throw UsageError("--spread-deg must be from 2 to 40");
  const Plan p = planIsoTest(model, cell, t);
  const auto violations = checkPlan(model, p.cell, p);
  if (!violations.empty()) {
    std::fprintf(stderr, "robocal iso-plan: the plan fails its safety check: %s\n",
                 describeViolation(violations.front()).c_str());
    return 1;
  }
  const std::string out = args.get("out", "iso.json");
  savePlanFile(out, p);
  std::printf(
      "ISO 9283-style test plan: %s, %d points (%d poses x %d cycles, %d of them warm-up), "
      "%d vias, robot time %.1f min; wrote %s\n",
      connectionName(p.shells.front().connection).c_str(), p.summary.points, kIsoPoseCount,
      t.cycles + t.warmup_cycles, t.warmup_cycles, p.summary.vias, p.summary.duration_s / 60,
      out.c_str());
  return 0;
}

int report(const std::vector<std::string>& argv) {
  const Args args(argv, {"model", "plan", "warmup-cycles"}, {"help", "json"});
  if (args.flag("help")) {
    std::fputs(kReportHelp, stdout);
    return 0;
  }
  const Model model = loadModelFile(args.required("model"));
  if (args.positional().size() != 1) throw UsageError("give one samples file");
  IsoConditions conditions{model.name, args.positional()[0], 0, 0, ""};
  int warmup = IsoTestSettings{}.warmup_cycles;
  if (args.has("plan")) {
    const Plan p = loadPlanFile(args.get("plan", ""));
    if (!p.iso)
      throw UsageError("--plan " + args.get("plan", "") +
                       " is not an ISO test's plan (its purpose is \"" +
                       planPurposeName(p.purpose) + "\")");
    warmup = p.iso->warmup_cycles;
    conditions.cycles_planned = p.iso->cycles;
    conditions.spread_deg = p.iso->spread_deg;
  }
  warmup = wholeArg(args, "warmup-cycles", warmup, 0, 1000);
  const std::vector<Sample> samples = loadSamplesFile(args.positional()[0]);
  IsoResult result;
  try {
    result = assessIsoTest(model, samples, warmup);
  } catch (const std::invalid_argument& e) {
    throw FormatError(args.positional()[0] + ": " + e.what());
  }
  if (args.flag("json"))
    std::printf("%s\n", isoJson(result, conditions).dump().c_str());
  else
    std::fputs(isoText(result, conditions).c_str(), stdout);
  return 0;
}

const RegisterCommand registered_plan({"iso-plan", "plan an ISO 9283-style test with the bar",
                                       plan});
const RegisterCommand registered_report({"iso-report",
                                         "the figures of an ISO 9283-style test from its samples",
                                         report});

}  // namespace
}  // namespace robocal::cli
