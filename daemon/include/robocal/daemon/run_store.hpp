// Run directories under <data_dir>/runs/<id>/: the plan, the samples (CSV, each row fsynced
// before the robot moves on), the event log (JSON lines), the run's state, re-plans and results.
// The samples file is the record of progress: a restarted daemon resumes from what it holds.
#pragma once

#include <robocal/kinematics/sample.hpp>

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace robocal::daemon {

class RunDir {
 public:
  explicit RunDir(std::string path);  // an existing run folder
  const std::string& path() const { return path_; }
  std::string id() const;
  std::string file(const std::string& name) const { return path_ + "/" + name; }

  // Appends one row (the samples format plus bar_spread_mm, time_s and approach_deg) and fsyncs
  // it. A run folder written before time_s or approach_deg was a column gets rows without it, as
  // its header says.
  void appendSample(const Sample& sample, double bar_spread_mm);
  // The samples on disk. A row torn by a crash (no line ending) is cut off first.
  std::vector<Sample> loadSamples();
  // Appends {"time": ISO-8601, ...event} to events.jsonl and fsyncs it.
  void logEvent(nlohmann::json event);
  // state.json: {"status": "running" | "paused" | "interrupted" | "done" | "aborted", ...}.
  nlohmann::json state() const;
  void setState(const nlohmann::json& state);
  void writeJson(const std::string& name, const nlohmann::json& value) const;

 private:
  std::string path_;
  // Whether the samples file has the time_s and approach_deg columns; its header read once.
  std::optional<bool> timed_, approach_recorded_;
};

// Whether the ball-bar may be attached to the robot, kept across runs and restarts in
// <data_dir>/bar.json: set when the daemon asks for a connection (the operator may seat the bar
// from then on), cleared only when the operator confirms a detach. A missing file means never
// attached; a damaged one counts as attached (doubt keeps the robot still until the operator
// confirms).
struct BarAttachment {
  bool maybe_attached = false;
  int ball = 0, chuck = 0;  // 1-based, 0 when not known
  double extension_mm = 0;
  std::string run;  // the run that attached it
  nlohmann::json toJson() const;
};

class RunStore {
 public:
  explicit RunStore(std::string data_dir);
  // A new run folder with its plan (JSON text) and an empty samples file.
  RunDir create(const std::string& plan_text);
  // Run ids, oldest first.
  std::vector<std::string> ids() const;
  RunDir open(const std::string& id) const;
  // The newest run whose state is neither done nor aborted.
  std::optional<std::string> latestUnfinished() const;
  // The newest fit on disk: the result-*.json of the newest run that has one, the highest "set"
  // in it. Files that cannot be read or parsed are skipped; their paths and errors go to
  // `skipped`, so a restarted daemon can say why an older result is served.
  std::optional<nlohmann::json> latestResult(std::vector<std::string>* skipped = nullptr) const;

  // The newest health check's verdict on disk: check.json of the newest run that has a readable
  // one (a CHECK object).
  std::optional<nlohmann::json> latestCheck() const;

  // The bar's attachment (durably written before the caller goes on). `problem` gets why a
  // damaged file was taken as "attached".
  BarAttachment barAttachment(std::string* problem = nullptr) const;
  void setBarAttachment(const BarAttachment& bar) const;

 private:
  std::string data_dir_;
  std::string runs_dir_;
};

}  // namespace robocal::daemon
