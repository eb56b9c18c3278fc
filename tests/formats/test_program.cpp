// Controller program files (program.hpp): each dialect's sample program (tests/formats/programs/,
// written after the layouts in docs/programs.md) read, rewritten with corrected locations, and
// read again: the corrected joints to the printed precision, every other line byte for byte.
#include <catch2/catch.hpp>

#include <robocal/formats/program.hpp>

#include "../cli/cli_helpers.hpp"

#include <algorithm>
#include <set>

using namespace robocal;
using namespace robocal::test;
using Catch::Matchers::Contains;

namespace {

std::string sample(const std::string& name) {
  return readTextFile(std::string(ROBOCAL_SOURCE_DIR "/tests/formats/programs/") + name);
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t nl = text.find('\n', at);
    const std::size_t end = nl == std::string::npos ? text.size() : nl + 1;
    out.push_back(text.substr(at, end - at));
    at = end;
  }
  return out;
}

// Every location moved by a different small amount; the rewritten file read back.
void rewritesExactly(const std::string& file, ProgramDialect dialect, std::size_t locations,
                     std::size_t literals) {
  INFO(file);
  const std::string text = sample(file);
  const ProgramFile program = parseProgram(text, dialect, file);
  REQUIRE(program.locations.size() == locations);
  CHECK(std::count_if(program.locations.begin(), program.locations.end(),
                      [](const ProgramLocation& l) { return l.literal; }) ==
        static_cast<long>(literals));
  std::vector<std::optional<JointsDeg>> corrected;
  for (std::size_t k = 0; k < locations; ++k) {
    JointsDeg q = program.locations[k].joints_deg;
    for (int j = 0; j < kJointCount; ++j)
      q[j] += 0.0123456 * static_cast<double>(k + 1) - 0.001 * j;
    corrected.push_back(q);
  }
  const std::string out = rewriteProgram(program, corrected);
  const ProgramFile back = parseProgram(out, dialect, "rewritten");
  REQUIRE(back.locations.size() == locations);
  std::set<int> location_lines;
  for (std::size_t k = 0; k < locations; ++k) {
    INFO(program.locations[k].name);
    CHECK(back.locations[k].line == program.locations[k].line);
    CHECK((back.locations[k].joints_deg - *corrected[k]).cwiseAbs().maxCoeff() <= 5e-7);
    location_lines.insert(program.locations[k].line);
  }
  const auto before = lines(text), after = lines(out);
  REQUIRE(before.size() == after.size());
  for (std::size_t i = 0; i < before.size(); ++i) {
    INFO("line " << i + 1);
    if (!location_lines.count(static_cast<int>(i) + 1)) CHECK(after[i] == before[i]);
  }
  // Nothing corrected: the file itself, byte for byte (endings and a final Ctrl-Z included).
  CHECK(rewriteProgram(program, std::vector<std::optional<JointsDeg>>(locations)) == text);
}

}  // namespace

TEST_CASE("programs: each dialect's locations are corrected and every other line kept") {
  rewritesExactly("pick_place.as", ProgramDialect::kAs, 4, 1);
  rewritesExactly("pick_place.v2", ProgramDialect::kVplus, 4, 1);
  rewritesExactly("pick_place.pg", ProgramDialect::kVal2, 4, 1);
}

TEST_CASE("programs: AS keeps external axes, the transformations and the program's header") {
  const ProgramFile p = parseProgram(sample("pick_place.as"), ProgramDialect::kAs, "p.as");
  const auto pick = std::find_if(p.locations.begin(), p.locations.end(),
                                 [](const ProgramLocation& l) { return l.name == "#pick"; });
  REQUIRE(pick != p.locations.end());
  std::vector<std::optional<JointsDeg>> corrected(p.locations.size());
  corrected[static_cast<std::size_t>(pick - p.locations.begin())] = JointsDeg::Constant(1.5);
  const std::string out = rewriteProgram(p, corrected);
  CHECK_THAT(out, Contains("#pick 1.500000 1.500000 1.500000 1.500000 1.500000 1.500000 "
                           "-2000.000000\n"));
  CHECK_THAT(out, Contains(".PROGRAM check() #9744\n"));  // a number, not a location
  // The location used and never defined is named with its line.
  REQUIRE(p.undefined.size() == 1);
  CHECK(p.undefined[0].name == "#not_taught");
  CHECK(p.undefined[0].line == 11);
}

TEST_CASE("programs: another dialect's file, or a broken location, is refused with its line") {
  CHECK_THROWS_WITH(parseProgram(sample("pick_place.as"), ProgramDialect::kVplus, "p.as"),
                    Contains("p.as:6: #[ is Kawasaki AS syntax: this file is not V+"));
  CHECK_THROWS_WITH(parseProgram(".JOINTS\n#a 1 2 3 4 5 6\n.END\n", ProgramDialect::kVal2, "x.pg"),
                    Contains("x.pg:1: .JOINTS is a Kawasaki AS location block: this file is not "
                             "VAL II"));
  CHECK_THROWS_WITH(parseProgram(sample("pick_place.v2"), ProgramDialect::kAs, "p.v2"),
                    Contains("p.v2:6: #PPOINT( is V+ or VAL II syntax"));
  CHECK_THROWS_WITH(parseProgram(".JOINTS\n#a 1 2 3 4 five 6\n.END\n", ProgramDialect::kAs, "x.as"),
                    Contains("x.as:2: a location line is '#name' and six joint values"));
  CHECK_THROWS_WITH(
      parseProgram(".JOINTS\n#a 1 2 3 4 5 6\n#a 1 2 3 4 5 6\n.END\n", ProgramDialect::kAs, "x.as"),
      Contains("x.as:3: location #a is defined twice"));
  CHECK_THROWS_WITH(
      parseProgram(".PROGRAM p()\n JMOVE #[1,2,3]\n.END\n", ProgramDialect::kAs, "x.as"),
      Contains("x.as:2: a joint literal #[...] holds six joint values"));
}
