// The samples file (docs/samples-format.md): CSV with a header row and the columns
// shell,ball,chuck,extension_mm,lat_deg,lon_deg,j1,...,j6,length_mm (extra columns ignored).
#pragma once

#include <robocal/formats/error.hpp>
#include <robocal/kinematics/sample.hpp>

#include <string>
#include <vector>

namespace robocal {

extern const char* const kSamplesHeader;  // the header line robocal writes, without newline

std::vector<Sample> parseSamples(const std::string& text, const std::string& source = "samples");
std::string formatSampleRow(const Sample& sample);              // one CSV line, without newline
std::string formatSamples(const std::vector<Sample>& samples);  // header + rows

std::vector<Sample> loadSamplesFile(const std::string& path);
void saveSamplesFile(const std::string& path, const std::vector<Sample>& samples);

}  // namespace robocal
