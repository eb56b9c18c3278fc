#include <robocal/formats/samples_csv.hpp>

#include <robocal/formats/csv.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string_view>

namespace robocal {
namespace {

constexpr std::array<const char*, 13> kColumns = {
    "shell", "ball", "chuck", "extension_mm", "lat_deg", "lon_deg",  "j1",
    "j2",    "j3",   "j4",    "j5",           "j6",      "length_mm"};
constexpr double kMaxTimeS = 1e12;     // Unix time for 30,000 years: printed in a short field
constexpr double kMaxApproachDeg = 1;  // as a model, a cell and --approach-deg take it

// An optional column's field: the value to `decimals` places, "" when not known.
std::string optionalField(const std::optional<double>& value, int decimals) {
  if (!value) return "";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, *value);
  return buf;
}

}  // namespace

const char* const kSamplesHeader =
    "shell,ball,chuck,extension_mm,lat_deg,lon_deg,j1,j2,j3,j4,j5,j6,length_mm";
const char* const kSamplesTimeColumn = "time_s";
const char* const kSamplesApproachColumn = "approach_deg";

std::vector<Sample> parseSamples(const std::string& text, const std::string& source) {
  std::vector<Sample> samples;
  std::array<int, kColumns.size()> column_of{};
  int time_column = -1;      // the optional time_s
  int approach_column = -1;  // the optional approach_deg
  size_t header_fields = 0;
  bool have_header = false;
  csv::forEachLine(text, [&](int line_no, std::string_view line) {
    const auto fields = csv::splitFields(line);
    const std::string where = source + ":" + std::to_string(line_no) + ": ";

    if (!have_header) {
      for (size_t c = 0; c < kColumns.size(); ++c) {
        column_of[c] = -1;
        for (size_t f = 0; f < fields.size(); ++f)
          if (fields[f] == kColumns[c]) column_of[c] = static_cast<int>(f);
        if (column_of[c] < 0)
          throw FormatError(where + "header has no column '" + kColumns[c] + "' (expected " +
                            kSamplesHeader + ")");
      }
      for (size_t f = 0; f < fields.size(); ++f)
        if (fields[f] == kSamplesTimeColumn)
          time_column = static_cast<int>(f);
        else if (fields[f] == kSamplesApproachColumn)
          approach_column = static_cast<int>(f);
      header_fields = fields.size();
      have_header = true;
      return;
    }

    if (fields.size() != header_fields)
      throw FormatError(where + "expected " + std::to_string(header_fields) + " fields, got " +
                        std::to_string(fields.size()));
    std::array<double, kColumns.size()> v{};
    for (size_t c = 0; c < kColumns.size(); ++c) {
      const std::string_view field = fields[column_of[c]];
      const std::optional<double> value = csv::number(field);
      if (!value)
        throw FormatError(where + "column '" + kColumns[c] + "': not a finite number: '" +
                          std::string(field) + "'");
      v[c] = *value;
    }
    auto whole = [&](size_t c, int lo, int hi) {
      if (v[c] != std::floor(v[c]) || v[c] < lo || v[c] > hi)
        throw FormatError(where + "column '" + kColumns[c] + "': expected a whole number from " +
                          std::to_string(lo) + " to " + std::to_string(hi) + ", got " +
                          std::string(fields[column_of[c]]));
      return static_cast<int>(v[c]);
    };
    Sample s;
    s.shell = whole(0, 0, 1000000);
    s.ball_index = whole(1, 1, kBallCount) - 1;
    s.chuck_index = whole(2, 1, kChuckCount) - 1;
    s.extension_mm = v[3];
    s.lat_deg = v[4];
    s.lon_deg = v[5];
    for (int j = 0; j < kJointCount; ++j) s.joints_deg[j] = v[6 + j];
    s.length_mm = v[12];
    if (s.length_mm <= 0) throw FormatError(where + "column 'length_mm': must be positive");
    if (time_column >= 0 && !fields[time_column].empty()) {  // empty: not known
      const std::string_view field = fields[time_column];
      s.time_s = csv::number(field);
      if (!s.time_s)
        throw FormatError(where + "column 'time_s': not a finite number: '" + std::string(field) +
                          "'");
      if (std::abs(*s.time_s) > kMaxTimeS)
        throw FormatError(where + "column 'time_s': expected seconds within +/-1e12, got " +
                          std::string(field));
    }
    if (approach_column >= 0 && !fields[approach_column].empty()) {  // empty: not known
      const std::string_view field = fields[approach_column];
      s.approach_deg = csv::number(field);
      if (!s.approach_deg || *s.approach_deg < 0 || *s.approach_deg > kMaxApproachDeg)
        throw FormatError(where + "column 'approach_deg': expected degrees from 0 to " +
                          std::to_string(static_cast<int>(kMaxApproachDeg)) + ", got '" +
                          std::string(field) + "'");
    }
    s.source = source;
    s.source_line = line_no;
    samples.push_back(std::move(s));
  });
  if (!have_header)
    throw FormatError(source + ": empty: no header row (expected " + std::string(kSamplesHeader) +
                      ")");
  return samples;
}

std::string formatSampleRow(const Sample& s) {
  char buf[512];
  std::snprintf(buf, sizeof buf, "%d,%d,%d,%.3f,%.4f,%.4f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f",
                s.shell, s.ball_index + 1, s.chuck_index + 1, s.extension_mm, s.lat_deg, s.lon_deg,
                s.joints_deg[0], s.joints_deg[1], s.joints_deg[2], s.joints_deg[3], s.joints_deg[4],
                s.joints_deg[5], s.length_mm);
  return buf;
}

std::string formatSampleTime(const Sample& s) {
  return optionalField(s.time_s, 3);
}

std::string formatSampleApproach(const Sample& s) {
  return optionalField(s.approach_deg, 4);
}

std::string formatSamples(const std::vector<Sample>& samples) {
  const bool timed = std::any_of(samples.begin(), samples.end(),
                                 [](const Sample& s) { return s.time_s.has_value(); });
  const bool approached = std::any_of(samples.begin(), samples.end(),
                                      [](const Sample& s) { return s.approach_deg.has_value(); });
  std::string out = std::string(kSamplesHeader) +
                    (timed ? std::string(",") + kSamplesTimeColumn : "") +
                    (approached ? std::string(",") + kSamplesApproachColumn : "") + "\n";
  for (const Sample& s : samples)
    out += formatSampleRow(s) + (timed ? "," + formatSampleTime(s) : "") +
           (approached ? "," + formatSampleApproach(s) : "") + "\n";
  return out;
}

std::optional<double> recordedApproachDeg(const std::vector<Sample>& samples,
                                          std::size_t* unrecorded) {
  std::optional<double> smallest;
  std::size_t missing = 0;
  for (const Sample& s : samples) {
    if (!s.approach_deg) {
      ++missing;
      continue;
    }
    smallest = smallest ? std::min(*smallest, *s.approach_deg) : *s.approach_deg;
  }
  if (unrecorded) *unrecorded = missing;
  if (missing > 0) return std::nullopt;
  return smallest;
}

std::vector<Sample> loadSamplesFile(const std::string& path) {
  return parseSamples(readTextFile(path), path);
}

void saveSamplesFile(const std::string& path, const std::vector<Sample>& samples) {
  writeTextFileAtomic(path, formatSamples(samples));
}

}  // namespace robocal
