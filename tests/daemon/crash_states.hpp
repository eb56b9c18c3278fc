// The crash-state explorer's pure half (after the ALICE study of application crash consistency,
// OSDI 2014): from the durable file operations a run made (formats/file_ops_log.hpp), every state
// a POSIX file system may be left in by a power cut, and the files of one such state.
//
// Each operation is made durable before the next begins (fsync of the file, and of its folder for
// a rename or a new file), so a cut during operation k leaves operations 0..k-1 whole and k:
// - not done at all (state `applied` = k);
// - an append torn after some of its bytes (the kernel wrote part of the page): `torn_bytes`;
// - a replace whose temporary file holds part of the new text, the rename not made.
// A truncate is either done or not (states k and k+1). Folders are taken as they were: robocal
// creates them before the files in them and never removes one.
#pragma once

#include <robocal/formats/file_ops_log.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace robocal::test {

struct CrashState {
  std::size_t applied = 0;                // operations [0, applied) whole
  std::optional<std::size_t> torn_bytes;  // operation `applied` cut after this many bytes
  std::string describe(const std::vector<FileOp>& ops) const {
    std::string out =
        "after " + std::to_string(applied) + " of " + std::to_string(ops.size()) + " operations";
    if (torn_bytes) {
      const FileOp& op = ops[applied];
      out += std::string(", then ") +
             (op.kind == FileOp::kAppend ? "an append to " : "a replace of ") +
             std::filesystem::path(op.path).filename().string() + " cut after " +
             std::to_string(*torn_bytes) + " of " + std::to_string(op.data.size()) + " bytes";
    }
    return out;
  }
};

// Every crash state of `ops`: each prefix, and each append torn after 1 byte, half and all but
// one byte, and each replace with half of its new text in the temporary file.
inline std::vector<CrashState> crashStates(const std::vector<FileOp>& ops) {
  std::vector<CrashState> states;
  for (std::size_t k = 0; k <= ops.size(); ++k) {
    states.push_back({k, std::nullopt});
    if (k == ops.size()) break;
    const std::size_t n = ops[k].data.size();
    if (ops[k].kind == FileOp::kAppend && n >= 2)
      for (const std::size_t cut : {std::size_t{1}, n / 2, n - 1})
        if (cut > 0 && cut < n) states.push_back({k, cut});
    if (ops[k].kind == FileOp::kReplace && n >= 2) states.push_back({k, n / 2});
  }
  return states;
}

// The files of `state` under `from` (the recording's folder), written under `to` instead.
inline void writeCrashState(const std::vector<FileOp>& ops, const CrashState& state,
                            const std::string& from, const std::string& to) {
  std::map<std::string, std::string> files;  // path -> content
  for (std::size_t k = 0; k < state.applied; ++k) {
    const FileOp& op = ops[k];
    if (op.kind == FileOp::kReplace) files[op.path] = op.data;
    if (op.kind == FileOp::kAppend) files[op.path] += op.data;
    if (op.kind == FileOp::kTruncate) files[op.path].resize(op.size);
  }
  if (state.torn_bytes) {
    const FileOp& op = ops[state.applied];
    const std::string part = op.data.substr(0, *state.torn_bytes);
    if (op.kind == FileOp::kAppend) files[op.path] += part;
    if (op.kind == FileOp::kReplace) files[op.path + ".tmp"] = part;
  }
  for (const auto& [path, content] : files) {
    if (path.rfind(from, 0) != 0) continue;
    const std::filesystem::path target = to + path.substr(from.size());
    std::filesystem::create_directories(target.parent_path());
    std::ofstream(target, std::ios::binary) << content;
  }
}

}  // namespace robocal::test
