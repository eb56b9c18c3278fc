#pragma once

#include <cstddef>
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
// Writes to path.tmp, fsyncs and renames over path, then fsyncs the folder, so a crash (a power
// cut too) leaves the old or the new file.
void writeTextFileAtomic(const std::string& path, const std::string& text);
// Appends text with one write and fsyncs it (and the folder when it creates the file): a crash
// leaves at most a torn last line.
void appendTextFileDurably(const std::string& path, const std::string& text);
// Cuts a last line that has no line ending (torn by a crash) off a line-per-record file, durably;
// the number of bytes cut (0: the file ends in a whole line, is empty or does not exist).
std::size_t cutTornLastLine(const std::string& path);

}  // namespace robocal
