#include <robocal/calibration/fit_pipeline.hpp>

#include <robocal/formats/error.hpp>

#include <filesystem>

namespace robocal {
namespace {

// A path as a shell reads it back: quoted when it holds anything but the plain characters.
std::string shellWord(const std::string& word) {
  if (!word.empty() && word.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                              "0123456789_-./+=:,@") == std::string::npos)
    return word;
  std::string quoted = "'";
  for (char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string solveCommand(const std::string& nominal_file,
                         const std::vector<std::string>& samples_files) {
  std::string command =
      "robocal solve --model " + (nominal_file.empty() ? "NOMINAL.json" : shellWord(nominal_file));
  for (const std::string& f : samples_files) command += " " + shellWord(f);
  if (samples_files.empty()) command += " SAMPLES.csv";
  return command + " --out calibrated.json --report report";
}

constexpr const char* kFixFirst =
    "Put right what the first problem says (the samples, the plan or the set-up), then fit again.";

}  // namespace

FitOutcome fitCalibration(const Model& nominal, std::vector<Sample> samples,
                          const AssessOptions& options, const FitOrigin& origin,
                          const WorkVolume& work) {
  FitOutcome o{assessFit(nominal, std::move(samples), options), nominal, {}, {}};
  o.calibrated = calibratedModel(o.fit, origin);
  o.accuracy = predictedAccuracy(nominal, o.calibrated, work);
  o.verdict = fitOnlyVerdict(o.fit);
  o.verdict.work_volume_rms_mm = o.accuracy.work_volume_rms_mm;
  o.verdict.whole_range_rms_mm = o.accuracy.whole_range_rms_mm;
  o.verdict.accuracy_note = o.accuracy.problem;
  return o;
}

void nextStepOffline(ResultVerdict& verdict, const std::string& nominal_file,
                     const std::vector<std::string>& samples_files) {
  if (!verdict.usable) {
    verdict.next_command = solveCommand(nominal_file, samples_files);
    verdict.next_why = kFixFirst;
  } else if (verdict.model_file.empty()) {
    verdict.next_command = solveCommand(nominal_file, samples_files);
    verdict.next_why = "Write the model: this fit wrote none (--out).";
  } else {
    verdict.next_command = "robocal compensate --model " + shellWord(verdict.model_file) +
                           " --targets TARGETS.csv --out corrected.csv";
    verdict.next_why =
        "Correct the joint targets of your programs with it (docs/compensation.md); robocal "
        "health checks later that the robot still matches it.";
  }
}

void nextStepDaemon(ResultVerdict& verdict, int model_version) {
  if (!verdict.usable) {
    verdict.next_command = "robocal start";
    verdict.next_why =
        "Put right what the first problem says (the plan, the set-up or the robot), "
        "then run again. robocald keeps this model as version " +
        std::to_string(model_version) + " and will not activate it.";
    return;
  }
  verdict.next_command = "robocal activate " + std::to_string(model_version);
  verdict.next_why =
      "Make it the model robocald's compensate requests use (or correct targets offline: robocal "
      "compensate --model " +
      shellWord(verdict.model_file) + " --targets TARGETS.csv --out corrected.csv).";
}

void writeFitReport(const FitOutcome& o, const std::string& dir) {
  ReportExtras extras;
  extras.verdict = o.verdict;
  // The map first, then the page that shows and links it.
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw FormatError(dir + ": cannot create the report folder: " + ec.message());
  if (o.accuracy.work_volume_report)
    extras.figures.push_back({"work_volume.svg",
                              "Predicted tool position error over the cell's work volume "
                              "(work_volume.json has every pose)",
                              writeWorkVolumeReport(dir, *o.accuracy.work_volume_report)});
  writeReport(dir, o.fit, o.calibrated, extras);
}

nlohmann::ordered_json fitResultJson(const FitOutcome& o) {
  nlohmann::ordered_json j = fitSummaryJson(o.fit);
  j["work_volume"] = o.accuracy.work_volume;
  j["whole_range"] = o.accuracy.whole_range;
  j["verdict"] = resultVerdictJson(o.verdict);
  return j;
}

}  // namespace robocal
