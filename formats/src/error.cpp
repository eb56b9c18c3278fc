#include <robocal/formats/error.hpp>
#include <robocal/formats/file_ops_log.hpp>

#include <fcntl.h>
#include <unistd.h>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace robocal {

std::string readTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FormatError(path + ": cannot open: " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw FormatError(path + ": read error");
  return text.str();
}

namespace {

// Writes all of text to fd; false with errno set on failure.
bool writeAll(int fd, const std::string& text) {
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return false;
    done += static_cast<size_t>(n);
  }
  return true;
}

// The folder holding `path`, fsynced: a file created or renamed there is only durable once its
// directory entry is (a power cut may otherwise keep the old name, or no file at all).
void syncParentDir(const std::string& path) {
  const std::string::size_type slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? "."
                          : slash == 0               ? "/"
                                                     : path.substr(0, slash);
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) throw FormatError(dir + ": cannot open to flush: " + std::strerror(errno));
  const bool synced = ::fsync(fd) == 0;
  const int err = errno;
  ::close(fd);
  if (!synced) throw FormatError(dir + ": cannot flush to disk: " + std::strerror(err));
}

}  // namespace

void writeTextFileAtomic(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw FormatError(tmp + ": cannot create: " + std::strerror(errno));
  if (!writeAll(fd, text)) {
    const int err = errno;
    ::close(fd);
    ::unlink(tmp.c_str());
    throw FormatError(tmp + ": write failed: " + std::strerror(err));
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    ::unlink(tmp.c_str());
    throw FormatError(tmp + ": cannot flush to disk: " + std::strerror(errno));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw FormatError(path + ": cannot replace: " + std::strerror(err));
  }
  syncParentDir(path);
  recordFileOp({FileOp::kReplace, path, text, 0});
}

void appendTextFileDurably(const std::string& path, const std::string& text) {
  int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  const bool created = fd < 0 && errno == ENOENT;
  if (created) fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw FormatError(path + ": cannot open for appending: " + std::strerror(errno));
  if (!writeAll(fd, text)) {
    const int err = errno;
    ::close(fd);
    throw FormatError(path + ": write failed: " + std::strerror(err));
  }
  const bool synced = ::fsync(fd) == 0;
  ::close(fd);
  if (!synced) throw FormatError(path + ": cannot flush to disk: " + std::strerror(errno));
  if (created) syncParentDir(path);
  recordFileOp({FileOp::kAppend, path, text, 0});
}

std::size_t cutTornLastLine(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) {
    if (errno == ENOENT) return 0;
    throw FormatError(path + ": cannot open: " + std::strerror(errno));
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } const closer{fd};
  const off_t size = ::lseek(fd, 0, SEEK_END);
  char last = '\n';
  if (size <= 0 || ::pread(fd, &last, 1, size - 1) != 1 || last == '\n') return 0;
  // Back to the last line ending, a block at a time.
  off_t keep = size - 1;
  char block[4096];
  while (keep > 0) {
    const off_t from = keep > static_cast<off_t>(sizeof block) ? keep - sizeof block : 0;
    const ssize_t n = ::pread(fd, block, static_cast<size_t>(keep - from), from);
    if (n <= 0) throw FormatError(path + ": read error: " + std::strerror(errno));
    const void* nl = ::memrchr(block, '\n', static_cast<size_t>(n));
    if (nl) {
      keep = from + (static_cast<const char*>(nl) - block) + 1;
      break;
    }
    keep = from;
  }
  if (::ftruncate(fd, keep) != 0 || ::fsync(fd) != 0)
    throw FormatError(path + ": cannot cut its torn last line: " + std::strerror(errno));
  recordFileOp({FileOp::kTruncate, path, {}, static_cast<std::size_t>(keep)});
  return static_cast<std::size_t>(size - keep);
}

}  // namespace robocal
