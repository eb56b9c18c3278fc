// A terminal session with the VAL II controller turned into a test transcript: the commands the
// user typed and the bytes the controller sent, written in the format of
// tests/drivers/transcripts/ (README.md there) so that tests/drivers/transcripts.cpp replays the
// file as it is. Pure: `robocal term` (cli/cmd_term.cpp) does the I/O and feeds this.
//
// The file: the header comments, an "@val {json}" line with the dialect keys of the config in
// use, then each exchange as "> COMMAND" and "< bytes" lines (escapeBytes, split after each line
// ending). An exchange ends when the reply collector (ValReplyCollector, fed the chunks as they
// arrived, as the driver is) sees the prompt come back; the rest of the chunk that completed it
// stays in the exchange. Under each exchange: a "# TODO expectation" comment for the technician
// and what the driver would see of the reply, so the replayer checks something from the start:
// "= lines N", or "! power_off|out_of_range|other" when there were error lines. An exchange the
// replayer would refuse (no prompt came back before the next command or the end of the session,
// or a reply read differently one byte at a time) is written commented out, with the reason.
// Bytes received with no command awaiting its reply are "# unsolicited: <escaped>" comments.
#pragma once

#include <robocal/drivers/config.hpp>
#include <robocal/drivers/protocol.hpp>

#include <nlohmann/json_fwd.hpp>

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace robocal::drivers {

// The keys of a ValConfig that describe the dialect, as an "@val" line carries them: all but the
// serial port and the driver's pacing (timeouts "_s", motion tolerances "_deg", still_polls,
// where_retries).
nlohmann::json valDialectJson(const ValConfig& config);

// Splits bytes after each line ending (CR, LF or CR LF), keeping the endings; a last piece
// without one is kept as it is.
std::vector<std::string> splitAfterLineEndings(std::string_view bytes);

class TranscriptRecorder {
 public:
  // `header` lines are written first as comments ("# " in front); `config` is the dialect the
  // terminal talks (its @val line, and how replies are collected and classified).
  TranscriptRecorder(ValConfig config, std::vector<std::string> header);
  TranscriptRecorder(const TranscriptRecorder&) = delete;
  TranscriptRecorder& operator=(const TranscriptRecorder&) = delete;

  // A command that was sent, without its line ending (std::invalid_argument if it holds a CR or
  // LF). The previous exchange ends here, complete or not.
  void command(const std::string& text);
  // Bytes received, in the chunks they arrived in.
  void received(std::string_view bytes);
  // True from command() until the prompt of its reply came back.
  bool awaitingReply() const;

  // The transcript so far (an exchange still awaiting its reply is written as not replayable).
  std::string text() const;
  // Exchanges so far that the replayer accepts, and those written commented out.
  int replayableExchanges() const;
  int unreplayableExchanges() const;

 private:
  struct Entry {
    bool exchange = false;  // else unsolicited bytes
    std::string command, bytes;
  };
  struct Verdict {
    bool replayable = false;
    std::string reason;    // when not replayable
    std::string todo;      // the TODO comment lines
    std::string expected;  // "= lines N" or "! kind"
  };
  Verdict judge(const Entry& e) const;
  void write(const Entry& e, std::string& out) const;

  ValDialect dialect_;
  std::vector<std::string> header_;
  std::vector<Entry> entries_;
  std::optional<ValReplyCollector> live_;  // the last command's reply as the driver reads it
};

// How the terminal shows received bytes: printable text and tabs as they are, each line ending
// (CR, LF or CR LF, even split across chunks) as one newline, other bytes escaped ("\x1B").
class ScreenText {
 public:
  std::string feed(std::string_view bytes);

 private:
  bool after_cr_ = false;
};

}  // namespace robocal::drivers
