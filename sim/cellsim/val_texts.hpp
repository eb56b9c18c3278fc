// What the simulated controller prints for its errors, per dialect preset (ValConfig::dialect):
// VAL II and V+ as "*Position out of range*", Kawasaki AS as "(P1013)Destination is out of
// motion range." (hardware.md; the AS codes other than P1000 are guesses). Pure text; the
// driver's error_regex, power_off_regex and out_of_range_regex of each preset must read them.
#pragma once

#include <robocal/drivers/protocol.hpp>

#include <string>

namespace robocal::cellsim {

enum class ValFault { kPowerOff, kOutOfRange, kUnknownCommand, kInvalidSpeed };

inline bool isKawasaki(const std::string& dialect) {
  return dialect == "kawasaki-as";
}

// An error line with the controller's own words for `message`.
inline std::string valErrorLine(const std::string& dialect, const std::string& message) {
  if (!isKawasaki(dialect)) return drivers::ValDialect::formatError(message);
  return message.rfind("(", 0) == 0 ? message : "(P0000)" + message;
}

inline std::string valErrorLine(const std::string& dialect, ValFault fault) {
  const bool as = isKawasaki(dialect);
  switch (fault) {
    case ValFault::kPowerOff:
      return valErrorLine(dialect, as ? "(P1000)Cannot execute program because motor power is OFF."
                                      : "Arm power off");
    case ValFault::kOutOfRange:
      return valErrorLine(
          dialect, as ? "(P1013)Destination is out of motion range." : "Position out of range");
    case ValFault::kUnknownCommand:
      return valErrorLine(dialect, as ? "(P0100)Syntax error." : "Unknown command");
    case ValFault::kInvalidSpeed:
      return valErrorLine(dialect, as ? "(P0101)Value is out of range." : "Invalid speed");
  }
  return "";
}

// The line a DO motion prints when it ends (AS; off for VAL II unless asked for).
inline const char* kCompletionLine = "DO motion completed.";
// The question a controller that just booted asks before any prompt.
inline const char* kBootQuestion = "Load VAL from floppy (Y/N)?";

}  // namespace robocal::cellsim
