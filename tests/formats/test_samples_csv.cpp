#include <catch2/catch.hpp>

#include <robocal/formats/samples_csv.hpp>

using namespace robocal;
using Catch::Matchers::Contains;

namespace {
Sample sample(int shell, int ball, int chuck, double length) {
  Sample s;
  s.shell = shell;
  s.ball_index = ball;
  s.chuck_index = chuck;
  s.extension_mm = 150;
  s.lat_deg = 30;
  s.lon_deg = 120;
  s.joints_deg << 1.5, -2.25, 170.125, 0.001, -45, 265.5;
  s.length_mm = length;
  return s;
}
}  // namespace

TEST_CASE("samples survive the round trip through CSV") {
  const std::vector<Sample> in = {sample(1, 0, 2, 250.123456), sample(2, 2, 0, 249.5)};
  const auto out = parseSamples(formatSamples(in), "s.csv");
  REQUIRE(out.size() == 2);
  CHECK(out[0].ball_index == 0);
  CHECK(out[0].chuck_index == 2);
  CHECK(out[1].shell == 2);
  CHECK(out[0].length_mm == Approx(250.123456).margin(1e-9));
  CHECK(out[0].joints_deg.isApprox(in[0].joints_deg, 1e-12));
  CHECK(out[1].source_line == 3);
  CHECK(out[1].source == "s.csv");
}

TEST_CASE("sample columns are found by name, extra columns are ignored") {
  const std::string text =
      "note,length_mm,j6,j5,j4,j3,j2,j1,lon_deg,lat_deg,extension_mm,chuck,ball,shell\n"
      "hello,200.5,6,5,4,3,2,1,90,45,0,3,2,7\r\n";
  const auto out = parseSamples(text);
  REQUIRE(out.size() == 1);
  CHECK(out[0].length_mm == 200.5);
  CHECK(out[0].joints_deg[0] == 1);
  CHECK(out[0].joints_deg[5] == 6);
  CHECK(out[0].ball_index == 1);
  CHECK(out[0].chuck_index == 2);
  CHECK(out[0].shell == 7);
}

TEST_CASE("malformed sample rows are reported with their line number") {
  const std::string header = std::string(kSamplesHeader) + "\n";
  const std::string good = "1,1,1,0,10,0,1,2,3,4,5,6,100\n";
  CHECK_THROWS_WITH(parseSamples("", "s.csv"), Contains("s.csv: empty"));
  CHECK_THROWS_WITH(parseSamples("shell,ball\n", "s.csv"),
                    Contains("s.csv:1: header has no column 'chuck'"));
  CHECK_THROWS_WITH(parseSamples(header + good + "1,1,1,0,10,0,1,2,3\n", "s.csv"),
                    Contains("s.csv:3: expected 13 fields, got 9"));
  CHECK_THROWS_WITH(parseSamples(header + "1,1,1,0,10,0,1,2,x3,4,5,6,100\n", "s.csv"),
                    Contains("s.csv:2: column 'j3': not a finite number: 'x3'"));
  CHECK_THROWS_WITH(parseSamples(header + "1,4,1,0,10,0,1,2,3,4,5,6,100\n", "s.csv"),
                    Contains("s.csv:2: column 'ball': expected a whole number from 1 to 3"));
  CHECK_THROWS_WITH(parseSamples(header + "1,1,1,0,10,0,1,2,3,4,5,6,inf\n", "s.csv"),
                    Contains("column 'length_mm': not a finite number"));
  CHECK_THROWS_WITH(parseSamples(header + "1,1,1,0,10,0,1,2,3,4,5,6,-1\n", "s.csv"),
                    Contains("s.csv:2: column 'length_mm': must be positive"));
}

TEST_CASE("the time of measurement is an optional column: kept when known, empty when not") {
  Sample timed = sample(1, 0, 0, 250.0);
  timed.time_s = 1764921600.125;  // Unix time, as the daemon writes it
  const Sample untimed = sample(1, 1, 1, 251.0);
  const std::string text = formatSamples({timed, untimed});
  CHECK_THAT(text, Contains(std::string(kSamplesHeader) + ",time_s\n"));
  const auto out = parseSamples(text, "s.csv");
  REQUIRE(out.size() == 2);
  REQUIRE(out[0].time_s);
  CHECK(*out[0].time_s == Approx(1764921600.125).margin(1e-3));
  CHECK_FALSE(out[1].time_s);

  // Without any time the file is the 13 columns it always was, and old files load unchanged.
  const std::string plain = formatSamples({untimed});
  CHECK(plain.find("time_s") == std::string::npos);
  CHECK_FALSE(parseSamples(plain)[0].time_s);

  const std::string header = std::string(kSamplesHeader) + ",time_s\n";
  CHECK_THROWS_WITH(parseSamples(header + "1,1,1,0,10,0,1,2,3,4,5,6,100,soon\n", "s.csv"),
                    Contains("s.csv:2: column 'time_s': not a finite number: 'soon'"));
  CHECK_THROWS_WITH(parseSamples(header + "1,1,1,0,10,0,1,2,3,4,5,6,100,1e13\n", "s.csv"),
                    Contains("s.csv:2: column 'time_s': expected seconds within +/-1e12"));
}

TEST_CASE("how each point was approached is an optional column the fit reads back") {
  Sample approached = sample(1, 0, 0, 250.0);
  approached.approach_deg = 0.02;
  Sample plain = sample(1, 1, 1, 251.0);
  plain.approach_deg = 0.0;
  const std::string text = formatSamples({approached, plain});
  CHECK_THAT(text, Contains(std::string(kSamplesHeader) + ",approach_deg\n"));
  const auto out = parseSamples(text, "s.csv");
  REQUIRE(out.size() == 2);
  REQUIRE(out[0].approach_deg);
  CHECK(*out[0].approach_deg == Approx(0.02).margin(1e-9));
  REQUIRE(out[1].approach_deg);
  CHECK(*out[1].approach_deg == 0);
  // A fit assumes the smallest recorded approach: a point reached with less took up less backlash.
  std::size_t unrecorded = 99;
  REQUIRE(recordedApproachDeg(out, &unrecorded));
  CHECK(*recordedApproachDeg(out) == 0);
  CHECK(unrecorded == 0);
  const std::vector<Sample> both = {out[0], out[0]};
  CHECK(*recordedApproachDeg(both) == Approx(0.02));

  // A file written before the record: nothing to go on, and the count says how many.
  const std::vector<Sample> mixed = {out[0], sample(2, 0, 0, 250)};
  CHECK_FALSE(recordedApproachDeg(mixed, &unrecorded));
  CHECK(unrecorded == 1);
  CHECK(formatSamples({sample(1, 0, 0, 250)}).find("approach_deg") == std::string::npos);

  // Time and approach together, in that order; each one's bad value named with its line.
  approached.time_s = 12.5;
  CHECK_THAT(formatSamples({approached}),
             Contains(std::string(kSamplesHeader) + ",time_s,approach_deg\n"));
  const std::string header = std::string(kSamplesHeader) + ",approach_deg\n";
  CHECK_THROWS_WITH(parseSamples(header + "1,1,1,0,10,0,1,2,3,4,5,6,100,-0.02\n", "s.csv"),
                    Contains("s.csv:2: column 'approach_deg': expected degrees from 0 to 1"));
  CHECK_THROWS_WITH(parseSamples(header + "1,1,1,0,10,0,1,2,3,4,5,6,100,2\n", "s.csv"),
                    Contains("column 'approach_deg'"));  // past what a model file holds
  CHECK_THROWS_WITH(parseSamples(header + "1,1,1,0,10,0,1,2,3,4,5,6,100,up\n", "s.csv"),
                    Contains("s.csv:2: column 'approach_deg'"));
  CHECK_FALSE(parseSamples(header + "1,1,1,0,10,0,1,2,3,4,5,6,100,\n")[0].approach_deg);
}
