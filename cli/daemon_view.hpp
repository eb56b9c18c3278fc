// How robocal shows robocald's objects to a person: plain text for a terminal or a log, one
// function per class (STATUS, PROMPT, STATE, PROGRESS, RESULT, RUNS, PLAN). Each names the command
// the operator types next where there is one. Pure formatting of the objects as proto/objects.hpp
// parses them: no I/O; `--json` bypasses it all.
#pragma once

#include <robocal/proto/objects.hpp>

#include <optional>
#include <string>

namespace robocal::cli {

// h:mm:ss
std::string clockText(double seconds);

// The pending prompt in large, plain words in a box, with the commands to type.
std::string promptText(const proto::Prompt& prompt);

// A STATE change ("state: paused - <reason>") and, where the run waits for the operator, what to
// type next.
std::string stateText(const proto::State& state_event);
std::string stateText(proto::RunState to, const std::string& reason);

// The live line: `[#####.....] 25/108  shell 3/9 B1C3  left 0:03:25  bar +0.090 mm`; with no run
// (no points planned) `no run in progress  bar +0.090 mm`.
std::string progressLine(const proto::Progress& progress, std::optional<double> bar_mm);

// `text` with every line longer than `width` broken at spaces (never inside a word unless a word
// alone is longer), continuation lines indented by two spaces: a terminal wraps mid-word.
std::string wrapText(const std::string& text, std::size_t width);

std::string statusText(const proto::Status& status);
std::string resultText(const proto::Result& result);
std::string runsText(const proto::Runs& runs);
// The MODELS list: one line a model, the active one starred.
std::string modelsText(const proto::Models& models);
std::string planText(const proto::Plan& plan);

}  // namespace robocal::cli
