// robocal-cellsim: a simulated robot cell behind two pseudo-terminals. One speaks the VAL II
// monitor dialect, the other the ball-bar reader's; behind them a "true" robot (a truth file: a
// model with the realism of robocal/sim/true_robot.hpp, backlash, compliance, warm-up in cell
// time, the LVDT's errors),
// joint motion at finite speed, the bar's true length around the connected ball and chuck, LVDT
// noise, the tool's ringing after a move (settling.hpp), joint quantisation, the bar's range,
// and injectable faults. A control channel (a unix
// socket and/or stdin) swaps the bar's connection and triggers faults.
//
// Everything runs on one Asio event loop; the protocol text is formatted and recognised with the
// drivers' own protocol helpers (robocal/drivers/protocol.hpp).
#pragma once

#include "settling.hpp"

#include <robocal/drivers/config.hpp>
#include <robocal/drivers/protocol.hpp>
#include <robocal/kinematics/model.hpp>

#include <string>

namespace robocal::cellsim {

struct Options {
  std::string model_path;  // the true robot (a truth file: model format, optional "realism")
  // Overrides the truth file's realism: "ideal", "typical" or a realism file; "" keeps it.
  std::string realism;
  std::string config_path;         // drivers config: the dialects to speak (defaults otherwise)
  std::string val_link, bar_link;  // symlinks to create to the pty slaves
  std::string control_path;        // unix socket for control commands
  bool stdin_control = false;      // also read control commands from stdin
  double time_scale = 1.0;         // motion runs this many times faster
  double joint_speed_deg_s = 60;   // at SPEED 100
  double speed_percent = 50;       // monitor speed at start
  // A path program's blend at each via, degrees of travel (robocal/kinematics/path_motion.hpp).
  double blend_deg = 2;
  drivers::Joints6 start_joints_deg{0, 45, -90, 0, 45, 0};
  double quantum_deg = 0.01;
  double noise_mm = 0.001;
  unsigned long seed = 1;
  std::string connection = "none";  // B1C1 ... or none
  double bar_mm = 100, extension_mm = 0;
  bool bar_here = false;   // bar length set so that the bar reads 0 at the start pose
  double range_mm = 1.5;   // LVDT travel each way
  SettlingModel settling;  // the tool's ringing after each move (settling.hpp); in cell time
  std::string bar_mode;    // polled | streamed (default: the config's)
  double stream_hz = 20;
  bool val_echo = true;
  // The controller's behaviours from hardware.md's evidence. The busy prompt (the config's
  // second prompt, VAL's "*") shows while a move runs whenever the config lists two prompts.
  bool val_sync_moves = false;        // DO MOVE's prompt comes back when the motion ends
  bool val_completion_lines = false;  // "DO motion completed." when a move ends (AS: always)
  bool val_boot_question = false;     // asks kBootQuestion until answered Y or N
  std::string val_eol = "\r\n";
  drivers::WhereLayout where_layout;
  int val_baud = 9600, bar_baud = 9600;  // the devices' rates; a driver at another rate sees garble
  // Faults (0 = off).
  long bar_garbage_every = 0, bar_drop_every = 0, bar_stall_after = 0, val_stall_after = 0;
  long val_garbage_every = 0, val_drop_every = 0;  // in replies with lines (WHERE)
  double stall_s = 2.0;
  long val_disconnect_after = 0, bar_disconnect_after = 0;
  double reconnect_after_s = 1.0;
  long val_error_on_command = 0;
  std::string val_error_text = "Position out of range";
  long estop_on_move = 0;
  bool bar_no_probe = false;
  bool verbose = false;
};

// Runs until SIGINT/SIGTERM or the control command "quit"; returns the exit code.
int run(const Options& options);

}  // namespace robocal::cellsim
