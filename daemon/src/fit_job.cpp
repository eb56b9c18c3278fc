#include "fit_job.hpp"

#include <robocal/calibration/fit_pipeline.hpp>
#include <robocal/formats/error.hpp>
#include <robocal/formats/health_report.hpp>
#include <robocal/formats/iso_report.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/formats/samples_csv.hpp>

#include <spdlog/spdlog.h>

#include <cmath>

namespace robocal::daemon {
namespace {

using json = nlohmann::json;

// The previous set's calibrated model of this run, to predict the new set before it is fitted.
std::optional<Model> previousSetModel(const json& last_result, const std::string& run,
                                      int& previous_set) {
  if (!last_result.contains("calibrated_file") || last_result.value("run", "") != run)
    return std::nullopt;
  try {
    previous_set = last_result.value("set", 0);
    return loadModelFile(last_result["calibrated_file"].get<std::string>());
  } catch (const std::exception& e) {  // the fit goes on, without the prediction
    spdlog::warn("the previous set's model cannot be read: {}", e.what());
    return std::nullopt;
  }
}

// The run's samples file, read as robocal solve and iso-report read it (here, while nothing
// appends to it): a RESULT is then `robocal solve --json` of that file plus the run's keys, by
// construction, and outliers are named by line. The run's own samples when the file disagrees.
std::vector<Sample> samplesAsFiled(const RunDir& dir, std::vector<Sample> samples) {
  std::vector<Sample> filed;
  try {
    filed = loadSamplesFile(dir.file("samples.csv"));
  } catch (const std::exception& e) {
    spdlog::warn("the samples file cannot be read back: {}", e.what());
  }
  if (filed.size() == samples.size()) return filed;
  spdlog::warn("the samples file holds {} samples, the run {}: using the run's", filed.size(),
               samples.size());
  return samples;
}

}  // namespace

void FitJob::launch(RunDir dir, std::vector<Sample> samples, double set_extension_mm, int set_index,
                    double approach_deg) {
  wait();
  int previous_set = 0;
  const json last = shared_.with([](const RunData& d) { return d.last_result; });
  std::optional<Model> previous = previousSetModel(last, dir.id(), previous_set);
  std::vector<Sample> fitted = samplesAsFiled(dir, std::move(samples));
  running_ = std::async(std::launch::async, [this, dir, fitted = std::move(fitted),
                                             set_extension_mm, set_index, previous, previous_set,
                                             approach_deg]() mutable {
    try {
      AssessOptions options;  // robocal solve's defaults
      if (previous) {
        HeldOutSamples held{{},
                            previous,
                            "set " + std::to_string(set_index) + " predicted by the set-" +
                                std::to_string(previous_set) + " fit"};
        for (const Sample& s : fitted)
          if (std::abs(s.extension_mm - set_extension_mm) < 1e-6) held.samples.push_back(s);
        if (!held.samples.empty()) options.validation = std::move(held);
      }
      FitOutcome outcome =
          fitCalibration(nominal_, std::move(fitted), options,
                         {dir.id(), {dir.file("samples.csv")}, approach_deg}, work_volume_);
      const FitAssessment& fit = outcome.fit;
      const std::string name = "set" + std::to_string(set_index);
      const std::string model_file = dir.file("calibrated-" + name + ".json");
      saveModelFile(model_file, outcome.calibrated);
      proto::ModelEntry entry;
      // Where the user works and beyond; a fit is still a fit without them.
      entry.work_volume_error_mm = outcome.accuracy.work_volume_rms_mm;
      if (!outcome.accuracy.work_volume_rms_mm)
        spdlog::warn("set {}: no work-volume accuracy: {}", set_index, outcome.accuracy.text);
      entry.date_utc = outcome.calibrated.provenance ? outcome.calibrated.provenance->date_utc : "";
      entry.run = dir.id();
      entry.set = set_index;
      entry.samples = static_cast<int>(fit.samples.size());
      entry.fit_rms_mm = fit.fit.after.rms_mm;
      entry.rank = fit.fit.identifiability.rank;
      entry.usable = fit.problems.empty();
      entry.problems = fit.problems;
      const int version = models_.add(outcome.calibrated, entry);
      outcome.verdict.model_file = model_file;
      nextStepDaemon(outcome.verdict, version);
      writeFitReport(outcome, dir.file("report-" + name));
      json result = fitResultJson(outcome);
      result["model_version"] = version;
      result["run"] = dir.id();
      result["set"] = set_index;
      result["extension_mm"] = set_extension_mm;
      result["calibrated_file"] = model_file;
      result["report_dir"] = dir.file("report-" + name);
      result["samples_file"] = dir.file("samples.csv");
      if (fit.validation)  // kept for clients of protocol 1.0; validation_* say the same
        result["prediction"] = {{"n", fit.validation->stats.count},
                                {"rms_mm", fit.validation->stats.rms_mm},
                                {"max_abs_mm", fit.validation->stats.max_abs_mm}};
      dir.writeJson("result-" + name + ".json", result);
      dir.logEvent({{"event", "result"},
                    {"set", set_index},
                    {"model_version", version},
                    {"rms_mm", fit.fit.after.rms_mm},
                    {"problems", fit.problems}});
      for (const std::string& problem : fit.problems)
        spdlog::warn("set {} fit not usable as a calibration: {}", set_index, problem);
      shared_.with([&](RunData& d) { d.last_result = result; });
      publish_(result, false);
    } catch (const std::exception& e) {
      spdlog::error("solver failed: {}", e.what());
      publish_(proto::toJson(proto::Error{std::string("solver failed: ") + e.what(), {}, {}}),
               false);
    }
  });
}

void FitJob::launchCheck(RunDir dir, std::vector<Sample> samples) {
  wait();
  running_ = std::async(std::launch::async, [this, dir, samples = std::move(samples)]() mutable {
    try {
      std::string problem;
      const auto active = models_.active(&problem);
      if (!active) throw std::runtime_error("no verdict: " + problem);
      const HealthVerdict verdict = assessHealth(active->model, samples, health_);
      proto::Check check;
      check.run = dir.id();
      check.model_version = active->version;
      check.date_utc = dateUtcNow();
      check.status = healthStatusName(verdict.status);
      check.text = healthVerdictText(verdict);
      check.verdict = healthVerdictJson(verdict);
      const json object = proto::toJson(check);
      dir.writeJson("check.json", object);
      json moved = json::array();
      for (const ParameterChange& c : verdict.moved) moved.push_back(c.text);
      dir.logEvent({{"event", "health_check"},
                    {"status", check.status},
                    {"model_version", check.model_version},
                    {"rms_mm", verdict.residuals.rms_mm},
                    {"rms_ratio", verdict.rms_ratio},
                    {"moved", moved}});
      models_.addCheck(active->version,
                       {dir.id(), check.date_utc, check.status, verdict.residuals.rms_mm});
      spdlog::info("health check of model {}: {} ({})", active->version, check.status,
                   verdict.reason);
      shared_.with([&](RunData& d) { d.last_check = object; });
      publish_(object, false);
    } catch (const std::exception& e) {
      spdlog::error("health check failed: {}", e.what());
      dir.logEvent({{"event", "health_check"}, {"error", e.what()}});
      publish_(proto::toJson(proto::Error{std::string("health check: ") + e.what(), {}, {}}),
               false);
    }
  });
}

void FitJob::launchIso(RunDir dir, std::vector<Sample> samples, IsoTestSettings settings) {
  wait();
  samples = samplesAsFiled(dir, std::move(samples));
  running_ =
      std::async(std::launch::async, [this, dir, samples = std::move(samples), settings]() mutable {
        try {
          const IsoResult iso = assessIsoTest(nominal_, samples, settings.warmup_cycles);
          const IsoConditions conditions{nominal_.name, dir.file("samples.csv"), settings.cycles,
                                         settings.spread_deg, dateUtcNow()};
          const json report = isoJson(iso, conditions);
          dir.writeJson("iso9283.json", report);
          writeTextFileAtomic(dir.file("iso9283.txt"), isoText(iso, conditions));
          json event = {{"class", "EVENT"},
                        {"event", "iso_report"},
                        {"run", dir.id()},
                        {"file", dir.file("iso9283.json")},
                        {"report", report}};
          dir.logEvent({{"event", "iso_report"}, {"file", dir.file("iso9283.json")}});
          spdlog::info("ISO 9283-style test {}: {} readings, report {}", dir.id(), iso.readings,
                       dir.file("iso9283.txt"));
          publish_(event, false);
        } catch (const std::exception& e) {
          spdlog::error("ISO test report failed: {}", e.what());
          dir.logEvent({{"event", "iso_report"}, {"error", e.what()}});
          publish_(proto::toJson(proto::Error{std::string("ISO test report: ") + e.what(), {}, {}}),
                   false);
        }
      });
}

}  // namespace robocal::daemon
