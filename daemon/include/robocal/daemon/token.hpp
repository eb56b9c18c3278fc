// The token that commands moving the robot must carry (docs/security.md). It is a random secret
// made at the daemon's first start and kept in a file. The file is private to the daemon's user
// (mode 0600) unless the daemon runs in the operators' group, when it is given to that group with
// mode 0640 so that operators in the group can read it. Errors are std::runtime_error naming the
// file.
#pragma once

#include <string>

namespace robocal::daemon {

// The group whose members may read the token: made by systemd/robocald.sysusers, the unit's
// Group=.
inline constexpr const char* kOperatorGroup = "robocal";

// Reads the token from `path`, first making it when the file does not exist: 24 bytes from
// /dev/urandom as 48 hex characters, O_EXCL, fsynced. A new file is given to `operator_group`
// with mode 0640 when that group exists and this process is in it, else it stays 0600. An
// existing file is never rewritten; a mode that lets anyone but the owner and `operator_group`
// read it is logged as a warning. A token shorter than 16 characters is refused.
std::string loadOrCreateToken(const std::string& path,
                              const std::string& operator_group = kOperatorGroup);

// Compares a client's token with the daemon's in time that does not depend on where they differ.
bool sameToken(const std::string& a, const std::string& b);

}  // namespace robocal::daemon
