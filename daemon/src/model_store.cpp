#include <robocal/daemon/model_store.hpp>

#include <robocal/formats/error.hpp>
#include <robocal/formats/model_json.hpp>

#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <regex>

namespace robocal::daemon {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// The versions with a model file, ascending.
std::vector<int> versionsIn(const std::string& dir) {
  std::vector<int> out;
  std::error_code ec;
  static const std::regex name(R"(model-(\d{4,9})\.json)");
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    std::smatch m;
    const std::string file = e.path().filename().string();
    if (std::regex_match(file, m, name)) out.push_back(std::stoi(m[1]));
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

std::string dateUtcNow() {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

ModelStore::ModelStore(std::string data_dir) : dir_(std::move(data_dir) + "/models") {
  fs::create_directories(dir_);
}

std::string ModelStore::file(int version, const char* suffix) const {
  char name[48];
  std::snprintf(name, sizeof name, "/model-%04d%s", version, suffix);
  return dir_ + name;
}

int ModelStore::add(const Model& model, proto::ModelEntry entry) {
  const std::lock_guard lock(mutex_);
  const auto versions = versionsIn(dir_);
  int version = versions.empty() ? 1 : versions.back() + 1;
  while (fs::exists(file(version, ".summary.json"))) ++version;  // a summary left by a crash
  entry.version = version;
  entry.file = file(version, ".json");
  entry.checks.clear();
  entry.active = false;
  proto::Models one;
  one.models.push_back(entry);
  writeTextFileAtomic(file(version, ".summary.json"), proto::toJson(one)["models"][0].dump(2));
  writeTextFileAtomic(entry.file, formatModel(model));
  return version;
}

std::optional<proto::ModelEntry> ModelStore::readEntry(int version) const {
  try {
    json summary = json::parse(readTextFile(file(version, ".summary.json")));
    const proto::Models wrapped = proto::parseObject<proto::Models>(
        {{"class", proto::Models::kClass}, {"active", nullptr}, {"models", {summary}}});
    proto::ModelEntry e = wrapped.models.at(0);
    e.version = version;
    e.file = file(version, ".json");
    const std::string checks = file(version, ".checks.jsonl");
    if (fs::exists(checks)) {
      const std::string text = readTextFile(checks);
      size_t pos = 0;
      while (pos < text.size()) {
        size_t end = text.find('\n', pos);
        if (end == std::string::npos) break;  // a line torn by a crash
        const json c = json::parse(text.substr(pos, end - pos));
        e.checks.push_back({c.value("run", ""), c.value("date_utc", ""), c.value("verdict", ""),
                            c.value("rms_mm", 0.0)});
        pos = end + 1;
      }
    }
    return e;
  } catch (const std::exception& ex) {
    spdlog::warn("models: version {} skipped: {}", version, ex.what());
    return std::nullopt;
  }
}

std::optional<int> ModelStore::activeVersion() const {
  const std::string path = dir_ + "/active.json";
  if (!fs::exists(path)) return std::nullopt;
  try {
    const json a = json::parse(readTextFile(path));
    const int v = a.at("version").get<int>();
    if (!fs::exists(file(v, ".json"))) throw std::runtime_error("no model file of that version");
    return v;
  } catch (const std::exception& e) {
    spdlog::warn("models: {} unusable, no model is active: {}", path, e.what());
    return std::nullopt;
  }
}

proto::Models ModelStore::list() const {
  const std::lock_guard lock(mutex_);
  proto::Models out;
  out.active = activeVersion();
  for (int v : versionsIn(dir_))
    if (auto e = readEntry(v)) {
      e->active = out.active == v;
      out.models.push_back(std::move(*e));
    }
  return out;
}

std::string ModelStore::activate(int version) {
  const std::lock_guard lock(mutex_);
  if (!fs::exists(file(version, ".json")))
    return "no model version " + std::to_string(version) + " (models lists them)";
  const auto entry = readEntry(version);
  if (!entry) return "model version " + std::to_string(version) + " cannot be read (see the log)";
  if (!entry->usable)
    return "model version " + std::to_string(version) + " is not usable as a calibration: " +
           (entry->problems.empty() ? std::string("(no reason recorded)") : entry->problems[0]);
  try {
    loadModelFile(file(version, ".json"));  // refuse what compensate could not read
  } catch (const std::exception& e) {
    return std::string("model version ") + std::to_string(version) + ": " + e.what();
  }
  writeTextFileAtomic(dir_ + "/active.json",
                      json{{"version", version}, {"date_utc", dateUtcNow()}}.dump() + "\n");
  cache_.reset();
  spdlog::info("models: version {} is now active", version);
  return {};
}

std::optional<ModelStore::Active> ModelStore::active(std::string* problem) const {
  const std::lock_guard lock(mutex_);
  const std::optional<int> v = activeVersion();
  if (!v) {
    if (problem) *problem = "no model is active (models lists them; activate makes one active)";
    return std::nullopt;
  }
  if (cache_ && cache_->version == *v) return cache_;
  try {
    cache_ = Active{*v, loadModelFile(file(*v, ".json"))};
    return cache_;
  } catch (const std::exception& e) {
    if (problem) *problem = e.what();
    return std::nullopt;
  }
}

void ModelStore::addCheck(int version, const proto::HealthCheckEntry& c) {
  const std::lock_guard lock(mutex_);
  appendTextFileDurably(
      file(version, ".checks.jsonl"),
      json{{"run", c.run}, {"date_utc", c.date_utc}, {"verdict", c.verdict}, {"rms_mm", c.rms_mm}}
              .dump() +
          "\n");
}

}  // namespace robocal::daemon
