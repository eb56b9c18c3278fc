// Pure protocol functions: framing, templates, WHERE formatting and parsing, bar lines.
#include <robocal/drivers/errors.hpp>
#include <robocal/drivers/protocol.hpp>

#include <catch2/catch.hpp>

using namespace robocal::drivers;

TEST_CASE("LineSplitter: CR, LF and CR LF, split anywhere", "[drivers][protocol]") {
  LineSplitter s;
  std::vector<std::string> lines;
  s.feed("a\r", lines);
  s.feed("\nb\nc\r\rd", lines);
  CHECK(lines == std::vector<std::string>{"a", "b", "c", ""});
  CHECK(s.pending() == "d");
  s.feed("\r\n.", lines);
  CHECK(lines.back() == "d");
  CHECK(s.pending() == ".");
}

TEST_CASE("Text helpers", "[drivers][protocol]") {
  CHECK(parseNumber("+1.5") == 1.5);
  CHECK(parseNumber("-.25") == -0.25);
  CHECK(parseNumber("12.") == 12.0);
  CHECK_FALSE(parseNumber("1e3"));
  CHECK_FALSE(parseNumber("nan"));
  CHECK_FALSE(parseNumber("-"));
  CHECK_FALSE(parseNumber("9O.0"));
  CHECK(formatFixed(-0.0001, 3) == "0.000");
  CHECK(unescapeBytes(escapeBytes("a\r\n\x01\xff\\")) == "a\r\n\x01\xff\\");
  CHECK_FALSE(isPrintableText("ab\x93"));
  CHECK(isPrintableText("ab\tc"));
}

TEST_CASE("Templates: expansion and recognition agree", "[drivers][protocol]") {
  const ValDialect d{ValConfig{}};
  const std::string cmd = d.moveCommand({1, -2.5, 3.25, 0, -0.0001, 266});
  CHECK(cmd == "DO MOVE #PPOINT(1.000,-2.500,3.250,0.000,0.000,266.000)");
  std::vector<std::string> fields;
  const std::regex re = templateRegex(ValConfig{}.move_joints_command, fields);
  std::smatch m;
  REQUIRE(std::regex_match(cmd, m, re));
  CHECK(fields == std::vector<std::string>{"j1", "j2", "j3", "j4", "j5", "j6"});
  CHECK(m[4].str() == "0.000");
  CHECK(std::regex_match(std::string("do move #ppoint( 1, 2 ,3,4,5,6 )"), re));
  CHECK(d.speedCommand(50) == "SPEED 50");
  CHECK(d.speedCommand(12.5) == "SPEED 12.5");
  CHECK_THROWS_AS(templateFields("SPEED {speed"), ProtocolError);
}

// Columns at least as wide as the values (as a controller prints them).
TEST_CASE("WHERE: every layout the simulator prints parses back", "[drivers][protocol]") {
  const ValConfig c;
  const Location6 loc{-569.455, 149.09, 441.045, 12.5, -45, 170};
  const Joints6 j{0.01, -90, 90, -110, 45.125, -266};
  for (int width : {9, 10, 14})
    for (int decimals : {2, 3, 4})
      for (int hand = 0; hand < 3; ++hand) {
        WhereLayout layout;
        layout.column_width = width;
        layout.decimals = decimals;
        layout.hand_column = hand > 0;
        layout.hand_blank = hand == 2;
        INFO("width " << width << " decimals " << decimals << " hand " << hand);
        const WhereReply w = parseWhere(formatWhere(c, layout, loc, j), c);
        for (int k = 0; k < 6; ++k) {
          CHECK(w.joints_deg[k] == Approx(j[k]).margin(0.51 * std::pow(10, -decimals)));
          REQUIRE(w.location);
          CHECK((*w.location)[k] == Approx(loc[k]).margin(0.51 * std::pow(10, -decimals)));
        }
      }
}

TEST_CASE("WHERE: missing pieces are explained", "[drivers][protocol]") {
  const ValConfig c;
  try {
    parseWhere({"X Y Z O A T", "1 2 3 4 5 6"}, c);
    FAIL("parsed");
  } catch (const ProtocolError& e) {
    CHECK_THAT(e.what(), Catch::Contains("JT1"));
  }
  CHECK_THROWS_AS(parseWhere({"JT1 JT2 JT3 JT4 JT5 JT6"}, c), ProtocolError);
  // The location block is optional.
  const WhereReply w = parseWhere({"JT1 JT2 JT3 JT4 JT5 JT6", "1 2 3 4 5 6"}, c);
  CHECK_FALSE(w.location);
  CHECK(w.joints_deg[5] == 6);
}

TEST_CASE("Reply collector: echo, prompt, errors", "[drivers][protocol]") {
  const ValDialect d{ValConfig{}};
  ValReplyCollector c(d, "SPEED 50");
  CHECK_FALSE(c.feed("SPEED 50\r"));
  CHECK_FALSE(c.feed("\n"));
  CHECK(c.feed("."));
  CHECK(c.echoSeen());
  CHECK(c.lines().empty());

  ValReplyCollector e(d, "X");
  e.feed("X\r\n*Position out of range*\r\n.");
  REQUIRE(e.errors().size() == 1);
  CHECK(e.errors()[0] == "Position out of range");
  CHECK_THROWS_AS(d.throwError("X", e.errors()[0]), OutOfRangeError);
  CHECK_THROWS_AS(d.throwError("X", "Arm power off"), ArmPowerOffError);
  CHECK_THROWS_AS(d.throwError("X", "Mystery"), ControllerError);
  CHECK(ValDialect::formatError("Arm power off") == "*Arm power off*");
}

TEST_CASE("Reply collector: what follows the reply in the same read is kept",
          "[drivers][protocol]") {
  // Found by CI: an E-stop report that arrived in the same read as a WHERE reply's prompt was
  // dropped, and the driver saw only an arm that had stopped short.
  const ValDialect d{ValConfig{}};
  ValReplyCollector c(d, "WHERE");
  CHECK(c.feed("WHERE\r\nJ1\r\n1.0\r\n.\r\n*Arm power off*\r\n."));
  CHECK(c.errors().empty());
  CHECK(c.lines() == std::vector<std::string>{"J1", "1.0"});
  LineSplitter rest;
  std::vector<std::string> lines;
  rest.feed(c.rest(), lines);
  CHECK(lines == std::vector<std::string>{"*Arm power off*"});
  CHECK(rest.pending() == ".");

  ValReplyCollector quiet(d, "WHERE");
  CHECK(quiet.feed("WHERE\r\nJ1\r\n1.0\r\n."));
  CHECK(quiet.rest().empty());
}

TEST_CASE("Bar lines: the simulator's formats parse back", "[drivers][protocol]") {
  for (const std::string format : {"mm_suffix", "mitutoyo", "gn"}) {
    BarConfig c;
    c.format = format;
    const BarDialect d(c);
    for (double v : {0.0, 0.01234, -1.2345, 1.4999}) {
      INFO(format << " " << v << " " << formatBarReading(format, v));
      const BarLine l = d.parse(formatBarReading(format, v));
      REQUIRE(l.kind == BarLineKind::kReading);
      CHECK(l.value_mm == Approx(v).margin(1e-4));
    }
    CHECK(d.parse(formatBarStatus(BarLineKind::kOverRange)).kind == BarLineKind::kOverRange);
    CHECK(d.parse(formatBarStatus(BarLineKind::kOverRange, true)).kind == BarLineKind::kOverRange);
    CHECK(d.parse(formatBarStatus(BarLineKind::kNoProbe)).kind == BarLineKind::kNoProbe);
    CHECK(d.parse(formatBarStatus(BarLineKind::kDeviceError)).kind == BarLineKind::kDeviceError);
    CHECK(d.parse("").kind == BarLineKind::kGarbage);
  }
}

TEST_CASE("Very long lines are not matched against the dialect's regexes", "[drivers][protocol]") {
  // Found with the fuzz harnesses' inputs made long: std::regex recursed once per character and
  // a 100 KB line overflowed the stack (the bar driver cuts lines at 1.3 KB, the VAL collector
  // did not cut them at all).
  const ValDialect val{ValConfig{}};
  ValReplyCollector c(val, "WHERE");
  CHECK(c.feed("WHERE\r\n*" + std::string(1000000, 'a') + "*\r\n*Arm power off*\r\n."));
  CHECK(c.errors() == std::vector<std::string>{"Arm power off"});
  CHECK(c.lines().size() == 1);
  CHECK(val.errorMessage("*" + std::string(kMaxRegexLineBytes - 2, 'a') + "*"));

  const BarDialect bar{BarConfig{}};
  CHECK(bar.parse(std::string(1000000, '1') + " MM").kind == BarLineKind::kGarbage);
  CHECK(bar.parse(std::string(1000, ' ') + "+1.5 MM").value_mm == 1.5);
}
