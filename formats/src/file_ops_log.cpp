#include <robocal/formats/error.hpp>
#include <robocal/formats/file_ops_log.hpp>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>

namespace robocal {
namespace {

const char* kindName(FileOp::Kind k) {
  return k == FileOp::kReplace ? "replace" : k == FileOp::kAppend ? "append" : "truncate";
}

std::string toHex(const std::string& bytes) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  out.reserve(2 * bytes.size());
  for (const unsigned char c : bytes) {
    out += digits[c >> 4];
    out += digits[c & 15];
  }
  return out;
}

std::string fromHex(const std::string& hex, const std::string& where) {
  if (hex.size() % 2) throw FormatError(where + ": odd number of hex digits");
  const auto value = [&](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    throw FormatError(where + ": not a hex digit");
  };
  std::string out;
  for (std::size_t i = 0; i < hex.size(); i += 2)
    out += static_cast<char>(value(hex[i]) * 16 + value(hex[i + 1]));
  return out;
}

}  // namespace

void recordFileOp(const FileOp& op) {
  static const char* log_path = std::getenv("ROBOCAL_FILE_OPS_LOG");
  if (!log_path || !*log_path) return;
  static std::mutex mutex;  // the run thread, the fit thread and the client loop all write
  nlohmann::json line = {{"op", kindName(op.kind)},
                         {"path", std::filesystem::absolute(op.path).lexically_normal().string()}};
  if (op.kind == FileOp::kTruncate)
    line["size"] = op.size;
  else
    line["hex"] = toHex(op.data);
  const std::lock_guard lock(mutex);
  if (FILE* f = std::fopen(log_path, "a")) {
    std::fputs((line.dump() + "\n").c_str(), f);
    std::fclose(f);
  }
}

std::vector<FileOp> loadFileOps(const std::string& log_path) {
  std::ifstream in(log_path);
  if (!in) throw FormatError(log_path + ": cannot open");
  std::vector<FileOp> ops;
  int line_number = 0;
  for (std::string text; std::getline(in, text);) {
    const std::string where = log_path + ":" + std::to_string(++line_number);
    try {
      const nlohmann::json j = nlohmann::json::parse(text);
      FileOp op;
      const std::string kind = j.at("op");
      op.kind = kind == "replace"    ? FileOp::kReplace
                : kind == "append"   ? FileOp::kAppend
                : kind == "truncate" ? FileOp::kTruncate
                                     : throw FormatError(where + ": unknown op '" + kind + "'");
      op.path = j.at("path");
      if (op.kind == FileOp::kTruncate)
        op.size = j.at("size");
      else
        op.data = fromHex(j.at("hex"), where);
      ops.push_back(std::move(op));
    } catch (const nlohmann::json::exception& e) {
      throw FormatError(where + ": " + e.what());
    }
  }
  return ops;
}

}  // namespace robocal
