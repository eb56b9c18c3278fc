// The daemon's token file: private to the daemon's user, or readable by the operators' group when
// the daemon runs in it; made once, never rewritten.
#include <catch2/catch.hpp>

#include "../cli/cli_helpers.hpp"

#include <robocal/daemon/token.hpp>

#include <grp.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <optional>
#include <vector>

using namespace robocal;
using namespace robocal::test;

namespace {

struct stat statOf(const std::string& path) {
  struct stat st {};
  REQUIRE(::stat(path.c_str(), &st) == 0);
  return st;
}

// A group this process is not in, if the system has one.
std::optional<std::string> foreignGroup() {
  std::vector<gid_t> mine(static_cast<std::size_t>(::getgroups(0, nullptr)) + 1);
  mine.resize(static_cast<std::size_t>(::getgroups(static_cast<int>(mine.size()), mine.data())));
  mine.push_back(::getegid());
  ::setgrent();
  std::optional<std::string> found;
  while (const group* g = ::getgrent())
    if (std::find(mine.begin(), mine.end(), g->gr_gid) == mine.end()) {
      found = g->gr_name;
      break;
    }
  ::endgrent();
  return found;
}

}  // namespace

TEST_CASE("the token is made once, 48 hex characters, mode 0600 without the operators' group") {
  TempDir dir;
  const std::string path = dir / "state/token";
  const std::string token = daemon::loadOrCreateToken(path, "no-such-group-robocal-test");
  CHECK(token.size() == 48);
  CHECK(token.find_first_not_of("0123456789abcdef") == std::string::npos);
  CHECK((statOf(path).st_mode & 0777) == 0600);
  CHECK(daemon::loadOrCreateToken(path, "no-such-group-robocal-test") == token);
  CHECK(daemon::sameToken(token, token));
  CHECK_FALSE(daemon::sameToken(token, token.substr(1)));
  CHECK_FALSE(daemon::sameToken(token, ""));
}

TEST_CASE("the token is readable by the operators' group when the daemon runs in it") {
  TempDir dir;
  const group* own = ::getgrgid(::getegid());
  REQUIRE(own);
  const std::string own_name = own->gr_name;
  const std::string path = dir / "token";
  daemon::loadOrCreateToken(path, own_name);
  const struct stat st = statOf(path);
  CHECK((st.st_mode & 0777) == 0640);
  CHECK(st.st_gid == ::getegid());
  // A group the daemon is not in gets nothing, even when it exists (root could chown to it).
  if (const auto other = foreignGroup()) {
    INFO("group " << *other);
    const std::string private_path = dir / "private-token";
    daemon::loadOrCreateToken(private_path, *other);
    CHECK((statOf(private_path).st_mode & 0777) == 0600);
  }
}

TEST_CASE("a short token is refused, an existing token file is never rewritten") {
  TempDir dir;
  const std::string path = dir / "token";
  std::ofstream(path) << "short\n";
  CHECK_THROWS_WITH(daemon::loadOrCreateToken(path), Catch::Contains("shorter than 16"));
  std::ofstream(path) << "a-token-an-operator-chose\n";
  CHECK(daemon::loadOrCreateToken(path) == "a-token-an-operator-chose");
}
