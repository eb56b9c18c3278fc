// The two serial protocols as pure functions: line framing, command templates, the VAL II monitor
// replies (echo, prompt, error lines, WHERE) and the ball-bar reader's lines. No I/O: the drivers
// feed these with received bytes, the simulator (robocal-cellsim) formats its output with them,
// and the tests feed them recorded transcripts.
#pragma once

#include <robocal/drivers/config.hpp>

#include <array>
#include <map>
#include <optional>
#include <regex>
#include <string>
#include <string_view>
#include <vector>

namespace robocal::drivers {

using Joints6 = std::array<double, 6>;    // joint readings, deg
using Location6 = std::array<double, 6>;  // X, Y, Z (mm), O, A, T (deg)

// The largest difference between two joint sets, joint by joint (deg).
double maxJointDiffDeg(const Joints6& a, const Joints6& b);

// ---------------------------------------------------------------------------------------------
// Lines and text

// Splits a byte stream into lines. CR, LF and CR LF each end one line (a CR LF is one ending,
// even when split across two feeds). What follows the last ending stays pending (a prompt has no
// line ending after it).
class LineSplitter {
 public:
  void feed(std::string_view bytes, std::vector<std::string>& lines);
  const std::string& pending() const { return pending_; }
  std::string takePending();
  void clear();

 private:
  std::string pending_;
  bool after_cr_ = false;
};

std::string trim(std::string_view text);
std::string toUpper(std::string_view text);
// Printable ASCII and tabs only (a line with anything else was garbled on the wire).
bool isPrintableText(std::string_view text);
// Raw received bytes that are text: printable ASCII, tabs and line endings.
bool looksLikeText(std::string_view bytes);
// Readable form of raw bytes for messages and logs: \r, \n, \t, \xNN.
std::string escapeBytes(std::string_view bytes);
// Inverse of escapeBytes (also accepts \\): used for transcripts and line endings in configs.
std::string unescapeBytes(std::string_view text);
// Lines longer than this are never matched against a dialect's regular expressions: no device
// line is that long, and std::regex recurses once per character (a 100 KB line overflowed the
// stack). They are neither VAL error lines nor bar readings or statuses (kGarbage).
inline constexpr std::size_t kMaxRegexLineBytes = 4096;
// Parses a whole token as a decimal number ("+1.5", "-.25", "12."); nullopt otherwise.
std::optional<double> parseNumber(std::string_view token);
std::string formatFixed(double value, int decimals);

// ---------------------------------------------------------------------------------------------
// Command templates: "SPEED {speed}" with named fields in braces.

// Field names in order of appearance; ProtocolError on an unclosed or empty brace.
std::vector<std::string> templateFields(const std::string& text);
std::string expandTemplate(const std::string& text,
                           const std::map<std::string, std::string>& fields);
// A regular expression matching an expanded template (spaces flexible, case-insensitive), with
// one numeric capture per field; `fields` receives the field names in capture order. The
// simulator uses it to recognise the commands the driver sends.
std::regex templateRegex(const std::string& text, std::vector<std::string>& fields);

// ---------------------------------------------------------------------------------------------
// VAL II monitor

// Most severe first: the order in which a reply's error lines are raised.
enum class ValErrorKind { kPowerOff, kOutOfRange, kOther };

// A ValConfig with its regular expressions compiled.
class ValDialect {
 public:
  explicit ValDialect(ValConfig config);
  const ValConfig& config() const { return config_; }

  std::string moveCommand(const Joints6& joints_deg) const;
  // The lines that write a path program through `steps` (val.path_*; the last step is where the
  // arm comes to rest), its execute command last; empty when the dialect offers none.
  std::vector<std::string> pathCommands(const std::vector<Joints6>& steps_deg) const;
  std::string speedCommand(double percent) const;
  // The message of an error line ("Position out of range"), or nullopt for other lines.
  std::optional<std::string> errorMessage(const std::string& line) const;
  ValErrorKind classify(const std::string& message) const;
  // The most severe of a reply's error messages (the first of equals); `messages` not empty.
  const std::string& mostSevere(const std::vector<std::string>& messages) const;
  // Throws ArmPowerOffError, OutOfRangeError or ControllerError for an error message.
  [[noreturn]] void throwError(const std::string& command, const std::string& message) const;
  // Any of the configured prompts (surrounding spaces aside).
  bool isPrompt(std::string_view text) const;
  // A prompt that may also be the first character(s) of an error line (VAL's "*" and
  // "*Arm power off*"): pending at the end of the received bytes it ends a reply only once the
  // line has been quiet (ValReplyCollector::tentative).
  bool couldStartError(std::string_view prompt) const;
  // `line` starts with a prompt and the rest is `rest` ("*WHERE", ". WHERE" for "WHERE").
  bool isPromptThen(const std::string& line, const std::string& rest) const;
  // A line the controller prints on its own that is to be dropped (val.ignore_regex).
  bool isIgnored(const std::string& line) const;
  // Text that asks the operator something ("Initialize?"), per val.question_regex.
  bool isQuestion(std::string_view text) const;
  // The top-level prompt and the one shown while a program or DO runs (the first again when
  // only one is configured). The simulator prints them.
  const std::string& idlePrompt() const { return config_.prompt.front(); }
  const std::string& busyPrompt() const { return config_.prompt.back(); }
  std::string describePrompts() const;  // '.' or '*' (for messages)
  // An error line as a VAL II controller prints it: "*Position out of range*".
  static std::string formatError(const std::string& message);

 private:
  ValConfig config_;
  std::regex error_re_, power_off_re_, out_of_range_re_, ignore_re_, question_re_;
};

// Gathers the controller's reply to one command from received bytes: drops the echo of the
// command (with or without a prompt before it), empty lines and ignored lines (completion
// messages), collects error lines, and is complete when a prompt comes back (alone on a line, or
// pending at the end without a line ending) or when the controller asks a question (text ending
// in "?" left without a line ending: question()). A pending prompt that could begin an error
// line ("*") only makes the reply tentative(): the caller calls quiet() when no byte has come
// for a moment (the driver: kPromptQuietMs), which completes it.
class ValReplyCollector {
 public:
  ValReplyCollector(const ValDialect& dialect, std::string command);
  // Returns true once the reply is complete.
  bool feed(std::string_view bytes);
  bool complete() const { return complete_; }
  bool tentative() const { return !complete_ && tentative_; }
  // The line has been quiet since the last feed: a tentative reply is complete. Returns complete().
  bool quiet();
  const std::vector<std::string>& lines() const { return lines_; }    // reply text lines
  const std::vector<std::string>& errors() const { return errors_; }  // error messages
  const std::string& raw() const { return raw_; }                     // every byte received
  bool echoSeen() const { return echo_seen_; }
  int ignored() const { return ignored_; }  // lines dropped by val.ignore_regex
  // The prompt that ended the reply ("." or "*"), or empty.
  const std::string& prompt() const { return prompt_; }
  // The question that ended the reply ("Load VAL from floppy (Y/N)?"), or empty.
  const std::string& question() const { return question_; }
  // Bytes that came after the end of the reply in the same read (an unsolicited message the
  // controller printed next, such as an E-stop report): the caller must not drop them.
  const std::string& rest() const { return rest_; }

 private:
  void line(const std::string& text);
  const ValDialect& dialect_;
  std::string command_;
  LineSplitter splitter_;
  std::vector<std::string> lines_, errors_;
  std::string raw_, rest_, question_, prompt_;
  bool complete_ = false, echo_seen_ = false, tentative_ = false;
  int line_endings_ = 0, ignored_ = 0;
};

struct WhereReply {
  Joints6 joints_deg{};
  std::optional<Location6> location;  // when the X Y Z O A T block is present and parses
};

// Finds the joint block by its header names (case-insensitive) and reads the next line of
// numbers below it, matching values to headers by whitespace-separated position (by column
// nearness when a column such as HAND is blank). Never by fixed columns. ProtocolError saying
// what is missing otherwise.
WhereReply parseWhere(const std::vector<std::string>& lines, const ValConfig& config);

// How the simulator prints WHERE; the parser accepts any of these.
struct WhereLayout {
  int column_width = 10;
  int decimals = 3;
  bool hand_column = false;  // a "HAND" header after T with a value (or blank)
  bool hand_blank = false;
  bool joints_first = false;  // the joint block before the location block (Kawasaki AS)
};
std::vector<std::string> formatWhere(const ValConfig& config, const WhereLayout& layout,
                                     const Location6& location, const Joints6& joints_deg);

// How long the line must be quiet before a tentative prompt ("*") ends a reply: several bytes'
// time at 9600 baud plus a USB adapter's latency timer (16 ms).
inline constexpr int kPromptQuietMs = 50;

// ---------------------------------------------------------------------------------------------
// Ball-bar reader

enum class BarLineKind { kReading, kOverRange, kNoProbe, kDeviceError, kGarbage };
const char* barLineKindName(BarLineKind kind);

struct BarLine {
  BarLineKind kind = BarLineKind::kGarbage;
  double value_mm = 0;  // kReading: captured value times unit_scale_mm
};

// A BarConfig with its regular expressions compiled.
class BarDialect {
 public:
  explicit BarDialect(BarConfig config);
  const BarConfig& config() const { return config_; }
  // Classifies one received line (without its line ending). A reading past range_mm (when set)
  // is kOverRange.
  BarLine parse(const std::string& line) const;
  std::string pollCommandBytes() const { return config_.poll_command + config_.send_line_ending; }

 private:
  BarConfig config_;
  std::regex value_re_, over_range_re_, no_probe_re_, error_re_;
};

// A reading as a reader of the given format preset prints it (value in the reader's unit).
std::string formatBarReading(const std::string& format, double value);
// Status lines: "OVER RANGE", "UNDER RANGE", "NO PROBE", "ERR 1".
std::string formatBarStatus(BarLineKind kind, bool under = false);

}  // namespace robocal::drivers
