// Replays the recorded transcripts in tests/drivers/transcripts/ through the protocol parsers:
// each VAL II reply whole and one byte at a time, each bar line, against the expectations
// written in the files (format: transcripts/README.md).
#include "transcript_replay.hpp"

#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/protocol.hpp>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace robocal::drivers;

namespace {

const std::string kDir = ROBOCAL_SOURCE_DIR "/tests/drivers/transcripts";

std::vector<double> numbers(const std::string& text) {
  std::istringstream in(text);
  std::vector<double> out;
  for (double v; in >> v;) out.push_back(v);
  return out;
}

struct Exchange {
  std::string command, bytes;
  std::vector<std::string> expectations;
  int line = 0;
  ValConfig config;
};

ValReplyCollector collect(const ValDialect& dialect, const Exchange& x, bool bytewise) {
  ValReplyCollector c(dialect, x.command);
  if (bytewise)
    for (char b : x.bytes) c.feed(std::string_view(&b, 1));
  else
    c.feed(x.bytes);
  c.quiet();  // the end of the recording: the line is quiet
  return c;
}

void checkVal(const Exchange& x, const std::string& file) {
  INFO(file << ":" << x.line << " > " << x.command);
  const ValDialect dialect(x.config);
  const ValReplyCollector whole = collect(dialect, x, false);
  const ValReplyCollector bytes = collect(dialect, x, true);
  REQUIRE(whole.complete());
  REQUIRE(bytes.complete());
  // Byte by byte, an error printed before the echo may end the reply at its prompt: the error is
  // the same, the rest is drained by the driver.
  if (whole.errors().empty()) CHECK(whole.lines() == bytes.lines());
  CHECK(whole.errors().empty() == bytes.errors().empty());
  for (const auto& e : x.expectations) {
    INFO(e);
    if (e.rfind("= joints", 0) == 0) {
      REQUIRE(whole.errors().empty());
      const auto want = numbers(e.substr(8));
      const WhereReply w = parseWhere(whole.lines(), x.config);
      for (int i = 0; i < 6; ++i) CHECK(w.joints_deg[i] == Approx(want.at(i)).margin(1e-9));
    } else if (e.rfind("= location", 0) == 0) {
      const auto want = numbers(e.substr(10));
      const WhereReply w = parseWhere(whole.lines(), x.config);
      REQUIRE(w.location.has_value());
      for (int i = 0; i < 6; ++i) CHECK((*w.location)[i] == Approx(want.at(i)).margin(1e-9));
    } else if (e.rfind("= lines", 0) == 0) {
      CHECK(whole.lines().size() == static_cast<std::size_t>(std::stoi(e.substr(7))));
      CHECK(whole.errors().empty());
    } else if (e == "! parse") {
      CHECK_THROWS_AS(parseWhere(whole.lines(), x.config), ProtocolError);
    } else if (e.rfind("= ignored", 0) == 0) {
      CHECK(whole.ignored() == std::stoi(e.substr(9)));
      CHECK(bytes.ignored() == whole.ignored());
    } else if (e.rfind("? ", 0) == 0) {
      CHECK(whole.question() == e.substr(2));
      CHECK(bytes.question() == whole.question());
      CHECK(whole.errors().empty());
    } else if (e.rfind("! ", 0) == 0) {
      // The most severe error line of the reply is the one the driver raises.
      REQUIRE(whole.errors().size() >= 1);
      const ValErrorKind kind = dialect.classify(dialect.mostSevere(whole.errors()));
      const std::string want = e.substr(2);
      CHECK(kind == (want == "power_off"      ? ValErrorKind::kPowerOff
                     : want == "out_of_range" ? ValErrorKind::kOutOfRange
                                              : ValErrorKind::kOther));
    } else {
      FAIL("unknown expectation " << e);
    }
  }
}

void checkBar(const BarConfig& config, const std::string& line, const std::string& e,
              const std::string& where) {
  INFO(where << " < " << escapeBytes(line) << " " << e);
  const BarLine parsed = BarDialect(config).parse(line);
  if (e.rfind("= value", 0) == 0) {
    REQUIRE(parsed.kind == BarLineKind::kReading);
    CHECK(parsed.value_mm == Approx(std::stod(e.substr(7))).margin(1e-9));
  } else {
    const std::string want = e.substr(2);
    CHECK(std::string(barLineKindName(parsed.kind)) == (want == "over_range"     ? "over range"
                                                        : want == "no_probe"     ? "no probe"
                                                        : want == "device_error" ? "device error"
                                                                                 : want));
  }
}

}  // namespace

int robocal::test::replayTranscript(const std::string& text, const std::string& file) {
  std::istringstream in(text);
  ValConfig val;
  BarConfig bar;
  std::vector<Exchange> exchanges;
  std::string bar_line;
  int checks = 0, n = 0;
  for (std::string line; std::getline(in, line);) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    const std::string rest = line.size() > 2 ? line.substr(2) : "";
    if (line.rfind("@val ", 0) == 0) {
      // Keys over the current dialect; a "dialect" key starts again from that preset.
      const auto patch = nlohmann::json::parse(line.substr(5));
      auto j = robocal::drivers::toJson(
          patch.contains("dialect") ? valPreset(patch["dialect"].get<std::string>()) : val);
      j.merge_patch(patch);
      val = valConfigFromJson(j);
    } else if (line.rfind("@bar ", 0) == 0) {
      bar = barConfigFromJson(nlohmann::json::parse(line.substr(5)));
    } else if (line[0] == '>') {
      exchanges.push_back({rest, "", {}, n, val});
    } else if (line[0] == '<') {
      if (exchanges.empty())
        bar_line = unescapeBytes(rest);
      else
        exchanges.back().bytes += unescapeBytes(rest);
    } else if (line[0] == '=' || line[0] == '!' || line[0] == '?') {
      if (exchanges.empty()) {
        checkBar(bar, bar_line, line, file + ":" + std::to_string(n));
        ++checks;
      } else {
        exchanges.back().expectations.push_back(line);
      }
    } else {
      FAIL(file << ":" << n << ": cannot read " << line);
    }
  }
  for (const auto& x : exchanges) {
    checkVal(x, file);
    checks += static_cast<int>(x.expectations.size());
  }
  return checks;
}

namespace {

int replay(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in);
  std::stringstream text;
  text << in.rdbuf();
  return robocal::test::replayTranscript(text.str(), std::filesystem::path(path).filename());
}

}  // namespace

TEST_CASE("Transcripts: VAL II dialect variants and the presets",
          "[drivers][protocol][transcripts]") {
  for (const char* name :
       {"val_default.txt", "val_no_echo_cr_hand.txt", "val_hand_blank_prompt_lines.txt",
        "val_errors.txt", "val_unparseable.txt", "val_star_prompt.txt", "val_questions.txt",
        "vplus.txt", "kawasaki_as.txt"}) {
    SECTION(name) {
      CHECK(replay(kDir + "/" + name) >= 2);
    }
  }
}

TEST_CASE("Transcripts: ball-bar reader formats", "[drivers][protocol][transcripts]") {
  for (const char* name : {"bar_mm_suffix.txt", "bar_mitutoyo.txt", "bar_gn.txt"}) {
    SECTION(name) {
      CHECK(replay(kDir + "/" + name) >= 5);
    }
  }
}
