// The samples file (docs/samples-format.md): CSV with a header row and the columns
// shell,ball,chuck,extension_mm,lat_deg,lon_deg,j1,...,j6,length_mm, and optionally time_s (when
// it was measured; an empty field: not known). Other columns are ignored.
#pragma once

#include <robocal/formats/error.hpp>
#include <robocal/kinematics/sample.hpp>

#include <string>
#include <vector>

namespace robocal {

extern const char* const kSamplesHeader;      // the 13 columns every file has, without newline
extern const char* const kSamplesTimeColumn;  // "time_s"

std::vector<Sample> parseSamples(const std::string& text, const std::string& source = "samples");
std::string formatSampleRow(const Sample& sample);   // the 13 columns, without newline
std::string formatSampleTime(const Sample& sample);  // the time_s field ("" when not known)
// Header + rows; with a time_s column when any sample has a time.
std::string formatSamples(const std::vector<Sample>& samples);

std::vector<Sample> loadSamplesFile(const std::string& path);
void saveSamplesFile(const std::string& path, const std::vector<Sample>& samples);

}  // namespace robocal
