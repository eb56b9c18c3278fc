// Typed errors of the serial drivers. Every message is meant to be read by a technician: it names
// the port or the device and says what was expected and what happened.
#pragma once

#include <stdexcept>
#include <string>

namespace robocal::drivers {

class DriverError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The configuration (JSON or struct) is invalid; the message names the key.
class ConfigError : public DriverError {
 public:
  using DriverError::DriverError;
};

// The port cannot be found or opened (missing, in use, no permission, bad settings).
class PortError : public DriverError {
 public:
  using DriverError::DriverError;
};

// The port went away while in use (USB adapter unplugged, cable pulled, pty closed).
class DisconnectedError : public DriverError {
 public:
  using DriverError::DriverError;
};

// The device did not answer within the configured time.
class TimeoutError : public DriverError {
 public:
  using DriverError::DriverError;
};

// A command's reply did not end within its time; echoSeen: the controller echoed the command.
class CommandTimeoutError : public TimeoutError {
 public:
  CommandTimeoutError(const std::string& what, bool echo_seen)
      : TimeoutError(what), echo_seen_(echo_seen) {}
  bool echoSeen() const { return echo_seen_; }

 private:
  bool echo_seen_;
};

// No valid ball-bar reading arrived within stale_after_s.
class StaleReadingError : public TimeoutError {
 public:
  using TimeoutError::TimeoutError;
};

// The device answered, but not in a form the configured dialect describes.
class ProtocolError : public DriverError {
 public:
  ProtocolError(const std::string& what, std::string raw)
      : DriverError(what), raw_(std::move(raw)) {}
  const std::string& raw() const { return raw_; }

 private:
  std::string raw_;
};

// The controller answered with an error line (`*...*`).
class ControllerError : public DriverError {
 public:
  ControllerError(const std::string& what, std::string controller_message)
      : DriverError(what), controller_message_(std::move(controller_message)) {}
  // The text between the stars, e.g. "Position out of range".
  const std::string& controllerMessage() const { return controller_message_; }

 private:
  std::string controller_message_;
};

// Arm power is off: the E-stop was pressed or power was never enabled (power_off_regex).
class ArmPowerOffError : public ControllerError {
 public:
  using ControllerError::ControllerError;
};

// The target is outside the arm's range or a joint limit (out_of_range_regex).
class OutOfRangeError : public ControllerError {
 public:
  using ControllerError::ControllerError;
};

// The controller asks a question instead of showing its prompt ("Load VAL from floppy (Y/N)?",
// "Initialize?", "CHANGE?"): the operator answers it on the controller's terminal; the drivers
// never do. controllerMessage() is the question.
class QuestionError : public ControllerError {
 public:
  using ControllerError::ControllerError;
};

// A move did not end at its target: it timed out or the arm stopped short.
class MotionError : public DriverError {
 public:
  using DriverError::DriverError;
};

// The ball-bar reader reported over/under range, no probe, or a device error.
class BarStatusError : public DriverError {
 public:
  using DriverError::DriverError;
};

}  // namespace robocal::drivers
