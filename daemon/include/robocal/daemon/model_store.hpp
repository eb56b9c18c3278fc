// The calibrated models robocald keeps, in <data_dir>/models/ (docs/robocald.md, "Models"):
//   model-0007.json          the model (model format, with its covariance): written once, never
//                            changed; the version is the number in its name
//   model-0007.summary.json  what `models` lists of it (run, set, samples, fit RMS, problems, the
//                            predicted work-volume error): written before the model, so a model
//                            file always has its summary
//   model-0007.checks.jsonl  its health-check history, one verdict a line, appended durably
//   active.json              {"version": 7, "date_utc": ...}: the model compensate uses
// Thread-safe: the fit thread adds, the client loop lists, activates and reads the active model.
// Damaged files are skipped with a warning (a damaged active.json means no active model), never
// a crash.
#pragma once

#include <robocal/kinematics/model.hpp>
#include <robocal/proto/objects.hpp>

#include <mutex>
#include <optional>
#include <string>

namespace robocal::daemon {

// Now as the models' and checks' dates: "2026-12-02T08:00:00Z" (UTC).
std::string dateUtcNow();

class ModelStore {
 public:
  explicit ModelStore(std::string data_dir);

  // Stores a new version of `model` with its summary (`entry`'s version, file, checks and active
  // are filled in here). Returns the version. Throws on an I/O error.
  int add(const Model& model, proto::ModelEntry entry);
  // Every stored model, oldest first, with the active one marked.
  proto::Models list() const;
  // Makes `version` the active model; returns an error for the operator, or "".
  std::string activate(int version);
  struct Active {
    int version = 0;
    Model model;
  };
  // The active model, read from its file (cached); nullopt when none is active or it cannot be
  // read (`problem` says why).
  std::optional<Active> active(std::string* problem = nullptr) const;
  // Appends a health-check verdict to the model's history.
  void addCheck(int version, const proto::HealthCheckEntry& check);

 private:
  std::string file(int version, const char* suffix) const;
  std::optional<proto::ModelEntry> readEntry(int version) const;
  std::optional<int> activeVersion() const;

  std::string dir_;
  mutable std::mutex mutex_;
  mutable std::optional<Active> cache_;
};

}  // namespace robocal::daemon
