#include <robocal/daemon/run_store.hpp>

#include <robocal/formats/error.hpp>
#include <robocal/formats/samples_csv.hpp>

#include <spdlog/spdlog.h>

#include <fcntl.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>

namespace robocal::daemon {
namespace {

namespace fs = std::filesystem;
constexpr const char* kSamplesFile = "samples.csv";
constexpr const char* kEventsFile = "events.jsonl";
constexpr const char* kStateFile = "state.json";
constexpr const char* kBarFile = "bar.json";

std::string isoNow() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t t = std::chrono::system_clock::to_time_t(now);
  const long ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  return std::string(buf) + "." + (ms < 100 ? (ms < 10 ? "00" : "0") : "") + std::to_string(ms) +
         "Z";
}

void syncDir(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace

RunDir::RunDir(std::string path) : path_(std::move(path)) {}

std::string RunDir::id() const {
  return fs::path(path_).filename().string();
}

void RunDir::appendSample(const Sample& s, double bar_spread_mm) {
  if (!timed_) {
    std::ifstream in(file(kSamplesFile));
    std::string header;
    std::getline(in, header);
    timed_ = header.find(std::string(",") + kSamplesTimeColumn) != std::string::npos;
    approach_recorded_ =
        header.find(std::string(",") + kSamplesApproachColumn) != std::string::npos;
  }
  char spread[32];
  std::snprintf(spread, sizeof spread, ",%.4f", bar_spread_mm);
  appendTextFileDurably(file(kSamplesFile),
                        formatSampleRow(s) + spread + (*timed_ ? "," + formatSampleTime(s) : "") +
                            (*approach_recorded_ ? "," + formatSampleApproach(s) : "") + "\n");
}

std::vector<Sample> RunDir::loadSamples() {
  const std::string path = file(kSamplesFile);
  if (const std::size_t cut = cutTornLastLine(path)) {
    spdlog::warn("{}: a row torn by a crash ({} bytes) removed", path, cut);
    logEvent({{"event", "torn_row_removed"}, {"file", kSamplesFile}, {"bytes", cut}});
  }
  return parseSamples(readTextFile(path), path);
}

void RunDir::logEvent(nlohmann::json event) {
  nlohmann::json line = {{"time", isoNow()}};
  line.update(event);
  const std::string path = file(kEventsFile);
  // A line torn by a crash is cut before the next is appended, or the two would be glued into
  // one that parses as neither.
  if (const std::size_t cut = cutTornLastLine(path)) {
    spdlog::warn("{}: a line torn by a crash ({} bytes) removed", path, cut);
    appendTextFileDurably(path, nlohmann::json{{"time", isoNow()},
                                               {"event", "torn_row_removed"},
                                               {"file", kEventsFile},
                                               {"bytes", cut}}
                                        .dump() +
                                    "\n");
  }
  appendTextFileDurably(path,
                        line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

nlohmann::json RunDir::state() const {
  try {
    return nlohmann::json::parse(readTextFile(file(kStateFile)));
  } catch (const std::exception&) {
    return {{"status", "interrupted"}};
  }
}

void RunDir::setState(const nlohmann::json& state) {
  writeJson(kStateFile, state);
}

void RunDir::writeJson(const std::string& name, const nlohmann::json& value) const {
  // Text from devices (a garbled reply quoted in a pause reason) may not be UTF-8: replaced, or
  // the dump throws and the state is never written.
  writeTextFileAtomic(file(name),
                      value.dump(1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

RunStore::RunStore(std::string data_dir)
    : data_dir_(std::move(data_dir)), runs_dir_(data_dir_ + "/runs") {
  std::error_code ec;
  fs::create_directories(runs_dir_, ec);
  if (ec) throw FormatError(runs_dir_ + ": cannot create: " + ec.message());
}

RunDir RunStore::create(const std::string& plan_text) {
  std::string id = isoNow().substr(0, 19);
  std::replace(id.begin(), id.end(), ':', '-');
  std::string path = runs_dir_ + "/" + id;
  for (int n = 2; fs::exists(path); ++n) path = runs_dir_ + "/" + id + "-" + std::to_string(n);
  fs::create_directories(path);
  RunDir run(path);
  writeTextFileAtomic(run.file("plan.json"), plan_text);
  writeTextFileAtomic(run.file(kSamplesFile), std::string(kSamplesHeader) + ",bar_spread_mm," +
                                                  kSamplesTimeColumn + "," +
                                                  kSamplesApproachColumn + "\n");
  run.setState({{"status", "running"}});
  syncDir(runs_dir_);
  return run;
}

std::vector<std::string> RunStore::ids() const {
  std::vector<std::string> out;
  for (const auto& entry : fs::directory_iterator(runs_dir_)) {
    if (!entry.is_directory()) continue;
    // create() writes state.json last: a folder without it was cut short by a crash before the
    // run began (nothing moved, nothing measured), and is no run to resume or list.
    if (!fs::exists(entry.path() / kStateFile)) {
      spdlog::warn("{}: an unfinished run folder (a crash while it was created): ignored",
                   entry.path().string());
      continue;
    }
    out.push_back(entry.path().filename().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

RunDir RunStore::open(const std::string& id) const {
  if (id.empty() || id.find('/') != std::string::npos || id.find("..") != std::string::npos ||
      !fs::is_directory(runs_dir_ + "/" + id))
    throw FormatError("no run '" + id + "'");
  return RunDir(runs_dir_ + "/" + id);
}

std::optional<std::string> RunStore::latestUnfinished() const {
  const auto all = ids();
  for (auto it = all.rbegin(); it != all.rend(); ++it) {
    const std::string status = open(*it).state().value("status", "interrupted");
    if (status != "done" && status != "aborted") return *it;
  }
  return std::nullopt;
}

std::optional<nlohmann::json> RunStore::latestCheck() const {
  const auto all = ids();
  for (auto it = all.rbegin(); it != all.rend(); ++it) {
    const std::string path = runs_dir_ + "/" + *it + "/check.json";
    if (!fs::exists(path)) continue;
    try {
      nlohmann::json c = nlohmann::json::parse(readTextFile(path));
      if (c.is_object() && c.value("class", "") == "CHECK") return c;
    } catch (const std::exception&) {  // an older check is served instead
    }
  }
  return std::nullopt;
}

std::optional<nlohmann::json> RunStore::latestResult(std::vector<std::string>* skipped) const {
  const auto all = ids();
  for (auto it = all.rbegin(); it != all.rend(); ++it) {
    std::optional<nlohmann::json> best;
    std::vector<fs::path> files;
    try {
      for (const auto& entry : fs::directory_iterator(runs_dir_ + "/" + *it)) {
        const std::string name = entry.path().filename().string();
        if (entry.is_regular_file() && name.starts_with("result-") && name.ends_with(".json"))
          files.push_back(entry.path());
      }
    } catch (const std::exception& e) {
      if (skipped) skipped->push_back(runs_dir_ + "/" + *it + ": " + e.what());
    }
    for (const fs::path& file : files) {
      try {
        nlohmann::json r = nlohmann::json::parse(readTextFile(file.string()));
        const bool usable = r.is_object() && r.value("class", "") == "RESULT" &&
                            r.value("set", nlohmann::json()).is_number_integer() &&
                            r.value("run", nlohmann::json()).is_string() &&
                            r.value("calibrated_file", nlohmann::json()).is_string();
        if (!usable)
          throw FormatError(
              "not a RESULT with a whole \"set\" and strings \"run\", \"calibrated_file\"");
        if (!best || r["set"].get<long>() > (*best)["set"].get<long>()) best = std::move(r);
      } catch (const std::exception& e) {
        if (skipped) skipped->push_back(file.string() + ": " + e.what());
      }
    }
    if (best) return best;
  }
  return std::nullopt;
}

nlohmann::json BarAttachment::toJson() const {
  return {{"maybe_attached", maybe_attached},
          {"ball", ball},
          {"chuck", chuck},
          {"extension_mm", extension_mm},
          {"run", run}};
}

BarAttachment RunStore::barAttachment(std::string* problem) const {
  const std::string path = data_dir_ + "/" + kBarFile;
  if (!fs::exists(path)) return {};
  try {
    const nlohmann::json j = nlohmann::json::parse(readTextFile(path));
    BarAttachment b;
    b.maybe_attached = j.at("maybe_attached").get<bool>();
    b.ball = j.value("ball", 0);
    b.chuck = j.value("chuck", 0);
    b.extension_mm = j.value("extension_mm", 0.0);
    b.run = j.value("run", "");
    return b;
  } catch (const std::exception& e) {
    if (problem) *problem = path + ": " + e.what() + "; the bar is taken as attached";
    BarAttachment doubt;
    doubt.maybe_attached = true;
    return doubt;
  }
}

void RunStore::setBarAttachment(const BarAttachment& bar) const {
  writeTextFileAtomic(data_dir_ + "/" + kBarFile, bar.toJson().dump(1) + "\n");
}

}  // namespace robocal::daemon
