// The simulated operator of a robocal-cellsim cell, for demos and tests: answers robocald's
// PROMPTs as a person at the cell would. It moves the bar (a cellsim control command), asks
// robocald to nudge the robot when the bar does not fit (as a person would jog it), then confirms.
// It speaks cellsim's control text to the cell and robocald's protocol (proto/) to the daemon.
#pragma once

#include <robocal/proto/client.hpp>
#include <robocal/proto/objects.hpp>

#include <functional>
#include <string>
#include <vector>

namespace robocal::sim {

// Sends one control command to robocal-cellsim and returns its reply line.
using CellsimControl = std::function<std::string(const std::string& command)>;

// Answers one PROMPT (connect or detach) on a watching client. Returns what it did, one line per
// action; throws proto::ClientError when the bar cannot be made to fit.
std::vector<std::string> answerPrompt(proto::Client& client, const proto::Prompt& prompt,
                                      const CellsimControl& control, const std::string& token,
                                      double bar_mm);

}  // namespace robocal::sim
