#include <robocal/formats/error.hpp>

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
}

void appendTextFileDurably(const std::string& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw FormatError(path + ": cannot open for appending: " + std::strerror(errno));
  if (!writeAll(fd, text)) {
    const int err = errno;
    ::close(fd);
    throw FormatError(path + ": write failed: " + std::strerror(err));
  }
  const bool synced = ::fsync(fd) == 0;
  ::close(fd);
  if (!synced) throw FormatError(path + ": cannot flush to disk: " + std::strerror(errno));
}

}  // namespace robocal
