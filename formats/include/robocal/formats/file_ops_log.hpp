// The durable file operations robocal makes (error.hpp's writeTextFileAtomic,
// appendTextFileDurably and cutTornLastLine), recorded for the crash-state explorer
// (tests/daemon/test_crash_states.cpp, scripts/crash-states.sh) when the environment variable
// ROBOCAL_FILE_OPS_LOG names a file: one JSON object a line, in the order the operations became
// durable, {"op": "replace"|"append", "path": absolute, "hex": the bytes written} or
// {"op": "truncate", "path", "size"}. Without the variable nothing is recorded.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace robocal {

struct FileOp {
  enum Kind { kReplace, kAppend, kTruncate } kind = kAppend;
  std::string path;      // absolute
  std::string data;      // the bytes written (replace: the whole file; append: what was added)
  std::size_t size = 0;  // truncate: the length kept
};

// Called by error.cpp's functions once an operation is durable (a no-op without the variable).
void recordFileOp(const FileOp& op);
// A recorded log, in order; FormatError naming the line when it cannot be read.
std::vector<FileOp> loadFileOps(const std::string& log_path);

}  // namespace robocal
