// robocal solve: identify the parameters from samples, with validation, outliers and a report.
#include "args.hpp"

#include <robocal/formats/model_json.hpp>
#include <robocal/formats/report.hpp>
#include <robocal/formats/samples_csv.hpp>
#include <robocal/solver/calibrate.hpp>

#include <cstdio>
#include <nlohmann/json.hpp>

namespace robocal::cli {
namespace {

constexpr const char* kHelp =
    R"(usage: robocal solve --model NOMINAL samples.csv [more.csv ...] --out CALIBRATED
                     [--validate HELD_OUT.csv] [--report DIR] [--json] [options]

Fits the 54-parameter model to ball-bar samples with Levenberg-Marquardt, starting from the
nominal model. The parameters the data cannot identify stay at their nominal values (listed).

  --model FILE            starting (nominal) model                                required
  --out FILE              calibrated model to write (model format)
  --validate FILE         held-out samples: RMS with the calibrated model, no refit
  --report DIR            write report.json and the residual figures (SVG) to DIR
  --outlier-sigmas K      report samples beyond K robust sigmas                   [5]
  --drop-outliers         drop the reported outliers and refit (listed, never silent)
  --truth FILE            a simulation's true model: report the ball-position error
                          of the nominal and calibrated models against it
  --max-iterations N      LM iteration cap                                         [100]
  --json                  one JSON object instead of text
)";

std::string where(const Sample& s) {
  return s.source + ":" + std::to_string(s.source_line);
}

int run(const std::vector<std::string>& argv) {
  const Args args(
      argv, {"model", "out", "validate", "report", "outlier-sigmas", "truth", "max-iterations"},
      {"json", "drop-outliers", "help"});
  if (args.flag("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  const Model nominal = loadModelFile(args.required("model"));
  if (args.positional().empty()) throw UsageError("no samples file given");
  std::vector<Sample> samples;
  for (const std::string& path : args.positional()) {
    auto more = loadSamplesFile(path);
    samples.insert(samples.end(), more.begin(), more.end());
  }
  if (samples.empty()) throw UsageError("the samples files hold no samples");
  const double k = args.number("outlier-sigmas", 5.0);
  if (k <= 0) throw UsageError("--outlier-sigmas must be positive");
  SolveOptions options;
  options.max_iterations = static_cast<int>(args.integer("max-iterations", 100));
  if (options.max_iterations < 1) throw UsageError("--max-iterations must be at least 1");

  SolveResult fit = solveCalibration(nominal, samples, options);
  std::vector<Outlier> outliers = findOutliers(fit.residuals, k);
  std::vector<Sample> dropped;
  if (args.flag("drop-outliers") && !outliers.empty()) {
    std::vector<Sample> kept;
    size_t next = 0;
    for (size_t i = 0; i < samples.size(); ++i) {
      if (next < outliers.size() && outliers[next].index == i) {
        dropped.push_back(samples[i]);
        ++next;
      } else {
        kept.push_back(samples[i]);
      }
    }
    samples.swap(kept);
    fit = solveCalibration(nominal, samples, options);
  }
  const Model calibrated = withParams(nominal, fit.params);
  const std::vector<double> ball_errors = predictedBallErrors(calibrated, fit.covariance, samples);
  double ball_error_rms = 0, ball_error_max = 0;
  for (double e : ball_errors) {
    ball_error_rms += e * e;
    ball_error_max = std::max(ball_error_max, e);
  }
  ball_error_rms = std::sqrt(ball_error_rms / ball_errors.size());
  const double endpoint_factor = barToEndpointErrorFactor(calibrated, samples);

  std::vector<Sample> validation;
  Eigen::VectorXd validation_residuals;
  if (args.has("validate")) {
    validation = loadSamplesFile(args.get("validate", ""));
    if (validation.empty()) throw UsageError("the --validate file holds no samples");
    validation_residuals = sampleResiduals(calibrated, validation);
  }
  TruthComparison truth_cmp;
  if (args.has("truth")) {
    const Model truth = loadModelFile(args.get("truth", ""));
    truth_cmp =
        compareWithTruth(nominal, calibrated, truth, validation.empty() ? samples : validation);
  }

  if (args.has("out")) saveModelFile(args.get("out", ""), calibrated);

  FitReport report{nominal,
                   calibrated,
                   samples,
                   fit,
                   outliers,
                   dropped,
                   validation,
                   validation_residuals,
                   ball_error_rms,
                   ball_error_max,
                   endpoint_factor,
                   truth_cmp,
                   k};
  const nlohmann::ordered_json summary = fitSummaryJson(report);
  if (args.has("report")) writeReport(args.get("report", ""), report);

  if (args.flag("json")) {
    std::printf("%s\n", summary.dump().c_str());
    return 0;
  }
  const auto& id = fit.identifiability;
  std::printf("samples: %zu from %zu file(s)\n", samples.size(), args.positional().size());
  std::printf("rank: %d of %d; %zu parameters not identified, fixed at their nominal values:\n  ",
              id.rank, kParamCount, id.redundant.size());
  for (int i : id.redundant) std::printf("%s ", paramName(i).c_str());
  std::printf("\niterations: %d, stopped: %s\n", fit.iterations, stopReasonText(fit.stop));
  std::printf(
      "RMS residual: %.4f mm before, %.4f mm after; max |residual| %.4f mm; sigma %.4f mm\n",
      fit.before.rms_mm, fit.after.rms_mm, fit.after.max_abs_mm, fit.sigma_mm);
  std::printf("condition number %.4g, O1 %.4g, O3 %.4g (column-scaled Jacobian)\n",
              fit.condition_number, fit.o1, fit.o3);
  std::printf(
      "predicted 1-sigma ball-position error over the data's poses: RMS %.4f mm, max %.4f mm\n",
      ball_error_rms, ball_error_max);
  std::printf("bar-to-endpoint error factor: %.2f (the paper estimates about 4)\n",
              endpoint_factor);
  if (outliers.empty()) {
    std::printf("outliers beyond %.1f robust sigmas: none\n", k);
  } else {
    std::printf("outliers beyond %.1f robust sigmas: %zu%s\n", k, outliers.size(),
                dropped.empty() ? " (kept; --drop-outliers drops them and refits)"
                                : " (dropped, refitted)");
    const auto& list = dropped.empty() ? samples : dropped;
    for (size_t i = 0; i < outliers.size(); ++i) {
      const Sample& s = dropped.empty() ? list[outliers[i].index] : list[i];
      std::printf("  %s: residual %+.4f mm (%.1f robust sigmas)\n", where(s).c_str(),
                  outliers[i].residual_mm, outliers[i].robust_sigmas);
    }
  }
  if (!validation.empty()) {
    const ResidualStats v = residualStats(validation_residuals);
    std::printf("validation (%s, %zu samples): RMS %.4f mm, max |residual| %.4f mm\n",
                args.get("validate", "").c_str(), v.count, v.rms_mm, v.max_abs_mm);
  }
  if (truth_cmp.poses > 0)
    std::printf(
        "ball-position error against the truth over %zu poses: nominal RMS %.4f mm, "
        "calibrated RMS %.4f mm (max %.4f mm)\n",
        truth_cmp.poses, truth_cmp.nominal_rms_mm, truth_cmp.calibrated_rms_mm,
        truth_cmp.calibrated_max_mm);
  if (args.has("out")) std::printf("wrote %s\n", args.get("out", "").c_str());
  if (args.has("report")) std::printf("report in %s\n", args.get("report", "").c_str());
  return 0;
}

const RegisterCommand registered({"solve", "identify the parameters from samples (LM)", run});

}  // namespace
}  // namespace robocal::cli
