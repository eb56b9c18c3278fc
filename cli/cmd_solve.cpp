// robocal solve: identify the parameters from samples, assess the fit (solver/assessment.hpp, the
// same assessment robocald makes of each shell set), and write the calibrated model only when the
// fit is usable as a calibration (or --allow-partial), with a report.
#include "args.hpp"
#include "model_args.hpp"

#include <robocal/calibration/fit_pipeline.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/formats/samples_csv.hpp>
#include <robocal/planner/cell_json.hpp>
#include <robocal/sim/true_robot_json.hpp>
#include <robocal/solver/assessment.hpp>

#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>

namespace robocal::cli {
namespace {

constexpr const char* kHelp =
    R"(usage: robocal solve --model NOMINAL samples.csv [more.csv ...] --out CALIBRATED
                     [--validate HELD_OUT.csv] [--report DIR] [--json] [options]

Fits the 54-parameter model to ball-bar samples with Levenberg-Marquardt, starting from the
nominal model. The parameters the data cannot identify stay at their nominal values (listed).
Prints the fit, the residual per shell (the worst shells named), and every parameter: nominal,
calibrated, change and 1-sigma.

The calibrated model is written only when the fit is usable: the rank reaches the robot's
independent parameters (36 for six revolute joints) and the predicted ball-position error is
below the nominal model's error on the samples. Otherwise robocal solve says what and why, writes
no model and exits with 3, unless --allow-partial is given.

  --model FILE            starting (nominal) model                                required
  --out FILE              calibrated model to write (model format, with its provenance)
  --allow-partial         write the model even when the fit is not usable (warns; the
                          model's provenance lists the problems)
  --validate FILE         held-out samples: RMS with the calibrated model, no refit
  --report DIR            write summary.html, report.json and the figures (SVG) to DIR
  --outlier-sigmas K      report samples beyond K robust sigmas                   [5]
  --drop-outliers         drop the reported outliers and refit (listed, never silent)
  --truth FILE            a simulation's true robot (simulate --truth-out): report the
                          ball-position error of the nominal and calibrated models
                          against it, its backlash, compliance and warm-up included
  --cell FILE             judge the predicted accuracy over this cell file's work_volume
                          (docs/compensation.md)              [the reference cell's]
  --approach-deg D        for samples that do not record it (no approach_deg column):
                          their points were each reached moving up by D deg in every
                          joint (the plan's motion.approach_deg). The model records it,
                          so that compensate reaches targets the same way
                                                           [the samples' record, else 0]
  --compliance            identify the gravity compliance of the joints that carry the
                          arm's weight with the 54 parameters, from the model's load
                          (its "compliance": link masses, the fixture; docs/accuracy.md);
                          kept when the data tell it from noise: the calibrated model
                          carries it, and compensate uses it. The default when the model
                          has the load; with this option a model without it is refused
  --rigid                 fit the 54 parameters alone, no compliance (its prediction over
                          the arm's whole range then leaves out the twist)
  --max-iterations N      LM iteration cap                                         [100]
  --json                  one JSON object instead of text

exit status: 0 fitted (model written with --out), 1 an unreadable input, 2 a usage error,
             3 the fit is not usable (rank below 36 or a predicted error above the
             nominal's): no model written
)";

constexpr int kExitNotUsable = 3;

std::string where(const Sample& s) {
  return s.source + ":" + std::to_string(s.source_line);
}

void printShells(const ShellTable& table) {
  std::printf("  shell  connection        n   RMS (mm)   max (mm)  mean (mm)  RMS/median\n");
  for (const ShellResiduals& s : table.shells)
    std::printf("  %5d  %-14s %4zu   %8.4f   %8.4f   %+8.4f      %6.2f%s\n", s.shell,
                shellConnectionText(s).c_str(), s.stats.count, s.stats.rms_mm, s.stats.max_abs_mm,
                s.stats.mean_mm, s.rms_to_median, s.stands_out ? "  !" : "");
  std::printf("  worst shells:");
  for (size_t k = 0; k < table.worst.size(); ++k) {
    const ShellResiduals& s = table.shells[table.worst[k]];
    std::printf("%s %d %s (RMS %.4f mm, %.1fx the median)", k ? "," : "", s.shell,
                shellConnectionText(s).c_str(), s.stats.rms_mm, s.rms_to_median);
  }
  std::printf("\n");
  for (const ShellResiduals& s : table.shells)
    if (s.stands_out) {
      std::printf("  ! an RMS at least %gx the median shell's: check those shells' set-up\n",
                  kShellStandsOut);
      break;
    }
}

void printParameters(const FitAssessment& a) {
  std::printf(
      "parameters: %zu estimated, %zu fixed at nominal (not identifiable from these data); "
      "1-sigma from the covariance\n",
      a.fit.free_params.size(), a.parameters.size() - a.fit.free_params.size());
  std::printf("  %-10s %-4s %14s %14s %12s %10s\n", "name", "unit", "nominal", "calibrated",
              "change", "1-sigma");
  for (const ParameterRow& p : a.parameters)
    std::printf("  %-10s %-4s %14s %14s %12s %10s\n", paramName(p.index).c_str(),
                paramUnitLabel(p.index), formatParamValue(p.index, p.nominal).c_str(),
                formatParamValue(p.index, p.calibrated).c_str(),
                formatParamValue(p.index, p.change(), true).c_str(),
                p.estimated ? formatParamValue(p.index, p.sigma).c_str() : "fixed");
}

void printText(const FitAssessment& a, const Model& calibrated, size_t files) {
  const SolveResult& fit = a.fit;
  const auto& id = fit.identifiability;
  std::printf("samples: %zu from %zu file(s), %zu connection(s): %s\n", a.samples.size(), files,
              a.connections.size(), connectionList(a.connections).c_str());
  std::printf(
      "rank: %d of %d (expected %d); %zu parameters not identified, fixed at their nominal "
      "values:\n  ",
      id.rank, kParamCount, id.expected, id.redundant.size());
  for (int i : id.redundant) std::printf("%s ", paramName(i).c_str());
  std::printf("\niterations: %d, stopped: %s\n", fit.iterations, stopReasonText(fit.stop));
  std::printf(
      "RMS residual: %.4f mm before, %.4f mm after; max |residual| %.4f mm; sigma %.4f mm\n",
      fit.before.rms_mm, fit.after.rms_mm, fit.after.max_abs_mm, fit.sigma_mm);
  std::printf("condition number %.4g, O1 %.4g, O3 %.4g (column-scaled Jacobian)\n",
              fit.condition_number, fit.o1, fit.o3);
  std::printf(
      "predicted 1-sigma ball-position error over the data's poses: RMS %.4f mm, max %.4f mm\n",
      a.predicted_ball_error_rms_mm, a.predicted_ball_error_max_mm);
  std::printf("bar-to-endpoint error factor: %.2f (the paper estimates about 4)\n",
              a.bar_to_endpoint_factor);
  if (a.outliers.empty()) {
    std::printf("outliers beyond %.1f robust sigmas: none\n", a.outlier_sigmas);
  } else {
    std::printf("outliers beyond %.1f robust sigmas: %zu%s\n", a.outlier_sigmas, a.outliers.size(),
                a.outliers_dropped ? " (dropped, refitted)"
                                   : " (kept; --drop-outliers drops them and refits)");
    for (const FlaggedOutlier& o : a.outliers)
      std::printf("  %s: residual %+.4f mm (%.1f robust sigmas)\n", where(o.sample).c_str(),
                  o.residual_mm, o.robust_sigmas);
  }
  std::printf("model adequacy: %s\n", a.adequacy.summary().c_str());
  if (a.adequacy.drift.places > 0) std::printf("drift: %s\n", a.adequacy.drift.summary().c_str());
  if (a.compliance) std::printf("gravity compliance: %s\n", a.compliance->summary().c_str());
  std::printf("\nresidual per shell after the fit:\n");
  printShells(a.shells);
  if (a.validation) {
    const ValidationResult& v = *a.validation;
    std::printf("\nvalidation, %s: %zu samples, RMS %.4f mm, max |residual| %.4f mm\n",
                v.description.c_str(), v.stats.count, v.stats.rms_mm, v.stats.max_abs_mm);
    printShells(v.shells);
  }
  if (a.truth)
    std::printf(
        "\nball-position error against the truth over %zu poses: nominal RMS %.4f mm, "
        "calibrated RMS %.4f mm (max %.4f mm)\n",
        a.truth->poses, a.truth->nominal_rms_mm, a.truth->calibrated_rms_mm,
        a.truth->calibrated_max_mm);
  std::printf("\n");
  printParameters(a);
  std::printf("\ncalibrated model: %s\n", calibrated.name.c_str());
}

// The path as provenance and the verdict's commands name it: absolute, without "." or "..".
std::string absolutePath(const std::string& path) {
  return std::filesystem::absolute(path).lexically_normal().string();
}

// Where the true robot of a simulation (robocal simulate --truth-out, cellsim) puts each sample's
// ball: its readings turned by backlash (from below when the calibration approached so, else its
// middle) and compliance, its links grown by the warm-up. A sample's time says how warm: simulate
// stamps seconds since its start, on the truth's own clock; a robocald run stamps Unix time while
// cellsim warms on its scaled clock (100x in the main job: warm within a minute), which the
// samples do not carry, so those are judged warm. Untimed samples: the truth as filed.
TrueBallMm trueBalls(TrueRobot truth, double approach_deg) {
  const Approach approach = approach_deg > 0 ? kPositiveApproach : Approach{};
  const Kinematics as_filed(truth.model);
  const Kinematics warm(truth.modelAt(std::numeric_limits<double>::infinity()));
  return [truth = std::move(truth), approach, as_filed, warm](const Sample& s) {
    constexpr double kUnixTimeFromS = 1e8;  // 3 years: no simulated run is that long
    const JointsDeg q = truth.effectiveReadings(s.joints_deg, approach);
    const Eigen::Vector3d& ball = truth.model.balls_mm[s.ball_index];
    if (!s.time_s) return as_filed.ballPosition(q, ball);
    if (*s.time_s >= kUnixTimeFromS) return warm.ballPosition(q, ball);
    return Kinematics(truth.modelAt(*s.time_s / 60.0)).ballPosition(q, ball);
  };
}

// How the samples' points were approached, as the model records it (compensate then writes the
// same pre-points): what the samples say, or --approach-deg for a file that does not say.
double samplesApproachDeg(const std::vector<Sample>& samples, std::optional<double> flag_deg) {
  std::size_t unrecorded = 0;
  const std::optional<double> recorded = recordedApproachDeg(samples, &unrecorded);
  if (recorded && flag_deg &&
      std::abs(*recorded - *flag_deg) > 5e-5) {  // the file keeps 4 decimals
    char text[160];
    std::snprintf(text, sizeof text,
                  "--approach-deg %.4f: the samples record %.4f deg (their approach_deg column): "
                  "leave the option out, the record is used",
                  *flag_deg, *recorded);
    throw UsageError(text);
  }
  if (recorded) return *recorded;
  if (flag_deg) return *flag_deg;
  std::fprintf(stderr,
               "robocal solve: warning: %zu of %zu samples do not record how their points were "
               "approached (no approach_deg: a file written before it was recorded); the model "
               "assumes no one-sided approach and compensate will write no pre-points. If the "
               "plan had motion.approach_deg D, fit again with --approach-deg D\n",
               unrecorded, samples.size());
  return 0;
}

int run(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"model", "out", "validate", "report", "outlier-sigmas", "truth",
                   "max-iterations", "cell", "approach-deg"},
                  {"json", "drop-outliers", "allow-partial", "compliance", "rigid", "help"});
  if (args.flag("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  const Model nominal = loadModelFile(args.required("model"));
  if (args.positional().empty()) throw UsageError("no samples file given");
  std::vector<Sample> samples;
  FitOrigin origin;
  for (const std::string& path : args.positional()) {
    auto more = loadSamplesFile(path);
    samples.insert(samples.end(), more.begin(), more.end());
    origin.samples_files.push_back(absolutePath(path));
  }
  if (samples.empty()) throw UsageError("the samples files hold no samples");
  origin.approach_deg = samplesApproachDeg(samples, approachDegArg(args));
  AssessOptions options;
  options.outlier_sigmas = args.number("outlier-sigmas", options.outlier_sigmas);
  if (options.outlier_sigmas <= 0) throw UsageError("--outlier-sigmas must be positive");
  options.drop_outliers = args.flag("drop-outliers");
  if (args.flag("compliance") && args.flag("rigid"))
    throw UsageError("--compliance and --rigid: give one");
  options.identify_compliance = !args.flag("rigid");
  if (args.flag("compliance") && !nominal.compliance)
    throw UsageError("--compliance: the model " + args.required("model") +
                     " has no \"compliance\" object (link masses and the fixture's: "
                     "docs/model-format.md)");
  options.solve.max_iterations =
      static_cast<int>(args.integer("max-iterations", options.solve.max_iterations));
  if (options.solve.max_iterations < 1) throw UsageError("--max-iterations must be at least 1");
  if (args.has("validate")) {
    const std::string path = args.get("validate", "");
    HeldOutSamples held{loadSamplesFile(path), std::nullopt,
                        "held-out samples " + path + " predicted by this fit"};
    if (held.samples.empty()) throw UsageError("the --validate file holds no samples");
    options.validation = std::move(held);
  }
  if (args.has("truth"))
    options.truth = trueBalls(loadTruthFile(args.get("truth", "")), origin.approach_deg);

  const CellConfig cell = args.has("cell") ? loadCellFile(args.get("cell", "")) : CellConfig{};

  FitOutcome outcome =
      fitCalibration(nominal, std::move(samples), options, origin, cell.work_volume);
  const FitAssessment& fit = outcome.fit;
  const Model& calibrated = outcome.calibrated;
  const bool refuse = !fit.problems.empty() && !args.flag("allow-partial");
  if (args.has("out") && !refuse) {
    saveModelFile(args.get("out", ""), calibrated);
    outcome.verdict.model_file = absolutePath(args.get("out", ""));
  }
  nextStepOffline(outcome.verdict, absolutePath(args.required("model")), origin.samples_files);
  if (args.has("report")) writeFitReport(outcome, args.get("report", ""));
  // Where the user works and beyond it (robocald's RESULT has the same, from the same code).
  const nlohmann::ordered_json summary = fitResultJson(outcome);
  const std::string& work_text = outcome.accuracy.text;

  if (args.flag("json")) {
    std::printf("%s\n", summary.dump().c_str());
  } else {
    printText(fit, calibrated, args.positional().size());
    std::printf("\n%s", work_text.c_str());
    if (args.has("out") && !refuse) std::printf("wrote %s\n", args.get("out", "").c_str());
    if (args.has("report"))
      std::printf("report in %s (summary.html)\n", args.get("report", "").c_str());
    std::printf("\n%s", resultVerdictText(outcome.verdict).c_str());
  }
  std::fflush(stdout);
  if (fit.problems.empty()) return 0;
  std::fprintf(stderr, "robocal solve: %s: the fit is not usable as a calibration:\n",
               refuse ? "refused" : "warning");
  for (const std::string& p : fit.problems) std::fprintf(stderr, "  - %s\n", p.c_str());
  if (refuse) {
    std::fprintf(stderr, "%s (--allow-partial writes it anyway, with these warnings)\n",
                 args.has("out") ? "no model written" : "no model would be written");
    return kExitNotUsable;
  }
  if (args.has("out"))
    std::fprintf(stderr, "written anyway (--allow-partial); its provenance lists these warnings\n");
  return 0;
}

const RegisterCommand registered({"solve", "identify the parameters from samples (LM)", run});

}  // namespace
}  // namespace robocal::cli
