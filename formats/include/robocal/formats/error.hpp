#pragma once

#include <stdexcept>
#include <string>

namespace robocal {

// A file or text that cannot be read as what it claims to be. The message names the source, the
// place in it (key path or line number) and the problem.
class FormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Whole file as a string; FormatError naming the path when it cannot be read.
std::string readTextFile(const std::string& path);
// Writes to path.tmp, fsyncs and renames over path, so a crash leaves the old or the new file.
void writeTextFileAtomic(const std::string& path, const std::string& text);
// Appends text with one write and fsyncs it: a crash leaves at most a torn last line.
void appendTextFileDurably(const std::string& path, const std::string& text);

}  // namespace robocal
