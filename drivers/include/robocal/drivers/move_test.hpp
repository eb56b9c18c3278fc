// The bring-up move test (`robocal probe --val PORT --move-test DEG`): on a new cell, before the
// daemon runs a whole plan, one small move per joint shows whether the configured dialect drives
// this controller. It reads WHERE, sets SPEED 10, moves each joint in turn by +DEG and back while
// polling WHERE, and reports what it saw: the prompt during a move, whether the move command
// returns before the motion ends, completion lines, the round-trip times, and a verdict.
//
// It moves the arm: the caller (the command line) asks for the operator's explicit confirmation
// first. A joint whose +DEG would pass the given limits moves by -DEG instead. Any error stops
// the test (ABORT is sent) and is reported with the joint it happened on.
#pragma once

#include <robocal/drivers/val.hpp>

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace robocal::drivers {

struct MoveTestOptions {
  double step_deg = 2;        // each joint moves by this and back (at most 10)
  double speed_percent = 10;  // SPEED sent first
  std::array<double, 6> min_deg{-360, -360, -360, -360, -360, -360};  // joint limits to respect
  std::array<double, 6> max_deg{360, 360, 360, 360, 360, 360};
};

struct JointMoveResult {
  int joint = 0;                       // 1..6
  double step_deg = 0;                 // signed
  double out_s = 0, back_s = 0;        // command sent to still at the target
  double command_reply_s = 0;          // the move command's round trip (its prompt)
  std::string prompt_after_move;       // the prompt that ended the move command's reply
  bool returned_while_moving = false;  // the first WHERE after the reply was short of the target
  int where_polls = 0;
  double error_deg = 0;  // at the end of the move out, largest joint difference to the target
};

struct MoveTestReport {
  bool ok = false;
  std::string error;  // what stopped the test, with the joint
  Joints6 start_deg{};
  std::vector<JointMoveResult> joints;
  std::vector<double> where_round_trip_s;
  long ignored_lines = 0, move_timeouts_watched = 0;
  // One paragraph: is the dialect right, and what the controller does.
  std::string verdict;
};

// Runs the test on a connected controller; `progress` (optional) sees one line per step.
MoveTestReport runMoveTest(ValController& val, const MoveTestOptions& options,
                           const std::function<void(const std::string&)>& progress = {});

}  // namespace robocal::drivers
