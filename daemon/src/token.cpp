#include <robocal/daemon/token.hpp>

#include <robocal/formats/error.hpp>

#include <spdlog/spdlog.h>

#include <fcntl.h>
#include <grp.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <vector>

namespace robocal::daemon {
namespace {

// The id of `name` when the group exists and this process is in it (effective or supplementary
// group): only then may the daemon give a file to it.
std::optional<gid_t> joinedGroup(const std::string& name) {
  std::vector<char> buffer(16384);
  group entry{};
  group* found = nullptr;
  if (::getgrnam_r(name.c_str(), &entry, buffer.data(), buffer.size(), &found) != 0 || !found)
    return std::nullopt;
  const gid_t gid = found->gr_gid;
  if (::getegid() == gid) return gid;
  const int count = ::getgroups(0, nullptr);
  std::vector<gid_t> groups(static_cast<std::size_t>(std::max(count, 0)));
  if (count > 0 && ::getgroups(count, groups.data()) == count &&
      std::find(groups.begin(), groups.end(), gid) != groups.end())
    return gid;
  return std::nullopt;
}

std::string randomToken() {
  unsigned char raw[24];
  const int rnd = ::open("/dev/urandom", O_RDONLY | O_CLOEXEC);
  const bool ok = rnd >= 0 && ::read(rnd, raw, sizeof raw) == static_cast<ssize_t>(sizeof raw);
  if (rnd >= 0) ::close(rnd);
  if (!ok) throw std::runtime_error("cannot read /dev/urandom for the token");
  std::string token;
  for (unsigned char b : raw) {
    char hex[3];
    std::snprintf(hex, sizeof hex, "%02x", b);
    token += hex;
  }
  return token;
}

}  // namespace

std::string loadOrCreateToken(const std::string& path, const std::string& operator_group) {
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  const std::optional<gid_t> group = joinedGroup(operator_group);
  if (!std::filesystem::exists(path)) {
    const std::string line = randomToken() + "\n";
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd < 0)
      throw std::runtime_error(path + ": cannot create the token file: " + std::strerror(errno));
    // fchmod, unlike open's mode, is not cut by the umask (the unit's is 0077).
    const bool shared =
        group && ::fchown(fd, static_cast<uid_t>(-1), *group) == 0 && ::fchmod(fd, 0640) == 0;
    const bool ok = ::write(fd, line.data(), line.size()) == static_cast<ssize_t>(line.size());
    ::fsync(fd);
    ::close(fd);
    if (!ok) throw std::runtime_error(path + ": cannot write the token");
    if (shared)
      spdlog::info("created token file {} (mode 640, readable by group {})", path, operator_group);
    else
      spdlog::info("created token file {} (mode 600)", path);
  }
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    const mode_t allowed = group && st.st_gid == *group ? 0640 : 0600;
    if (st.st_mode & 0077 & ~allowed)
      spdlog::warn(
          "token file {} is open to others (mode {:o}); chmod 600 it, or 640 with group {}", path,
          st.st_mode & 0777, operator_group);
  }
  std::string token = readTextFile(path);
  while (!token.empty() && (token.back() == '\n' || token.back() == '\r' || token.back() == ' '))
    token.pop_back();
  if (token.size() < 16)
    throw std::runtime_error(path + ": the token is shorter than 16 characters");
  return token;
}

bool sameToken(const std::string& a, const std::string& b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (std::size_t i = 0; i < a.size(); ++i) diff |= a[i] ^ b[i % std::max<size_t>(1, b.size())];
  return diff == 0;
}

}  // namespace robocal::daemon
