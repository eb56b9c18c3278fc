// The samples file (docs/samples-format.md): CSV with a header row and the columns
// shell,ball,chuck,extension_mm,lat_deg,lon_deg,j1,...,j6,length_mm, and optionally time_s (when
// it was measured) and approach_deg (how far every joint rose into the point from its pre-point;
// 0: no one-sided approach); an empty field: not known. Other columns are ignored.
#pragma once

#include <robocal/formats/error.hpp>
#include <robocal/kinematics/sample.hpp>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace robocal {

extern const char* const kSamplesHeader;          // the 13 columns every file has, without newline
extern const char* const kSamplesTimeColumn;      // "time_s"
extern const char* const kSamplesApproachColumn;  // "approach_deg"

std::vector<Sample> parseSamples(const std::string& text, const std::string& source = "samples");
std::string formatSampleRow(const Sample& sample);       // the 13 columns, without newline
std::string formatSampleTime(const Sample& sample);      // the time_s field ("" when not known)
std::string formatSampleApproach(const Sample& sample);  // the approach_deg field ("" unknown)
// Header + rows; with a time_s column when any sample has a time, an approach_deg column when any
// sample records its approach.
std::string formatSamples(const std::vector<Sample>& samples);

// The approach the samples record, as a fit must assume it: the smallest of them (a point reached
// with less approach takes up less backlash); none when any sample does not say (their count in
// `unrecorded`).
std::optional<double> recordedApproachDeg(const std::vector<Sample>& samples,
                                          std::size_t* unrecorded = nullptr);

std::vector<Sample> loadSamplesFile(const std::string& path);
void saveSamplesFile(const std::string& path, const std::vector<Sample>& samples);

}  // namespace robocal
