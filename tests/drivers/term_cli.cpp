// `robocal term` against robocal-cellsim over real ptys: typed lines reach the controller, its
// replies reach stdout, and --record writes a transcript the replayer accepts as it is.
#include "cellsim_process.hpp"
#include "transcript_replay.hpp"

#include <robocal/drivers/config.hpp>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <sys/wait.h>

#include <cstdio>
#include <fstream>
#include <sstream>

using robocal::test::CellSimProcess;
using robocal::test::runShell;

namespace {

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The numbers after `prefix` on the line that starts with it.
std::vector<double> numbersAfter(const std::string& text, const std::string& prefix) {
  const auto at = text.find("\n" + prefix);
  REQUIRE(at != std::string::npos);
  const auto begin = at + 1 + prefix.size();
  std::istringstream in(text.substr(begin, text.find('\n', begin) - begin));
  std::vector<double> out;
  for (double v; in >> v;) out.push_back(v);
  return out;
}

}  // namespace

TEST_CASE("robocal term: a session with the controller, recorded as a test transcript",
          "[drivers][term][cli]") {
  CellSimProcess sim;
  const std::string config = sim.dir() + "/drivers.json";
  std::ofstream(config) << robocal::drivers::toJson(sim.driversConfig()).dump(2);
  const std::string record = sim.dir() + "/first-day.txt";
  const std::string term = ROBOCAL_BINARY_DIR "/cli/robocal term --config " + config + " --val " +
                           sim.valPath() + " --record " + record;

  SECTION("typed lines are sent, replies shown and recorded") {
    const auto [code, out] = runShell("printf 'WHERE\\nSPEED 20\\n' | " + term);
    INFO(out);
    CHECK(code == 0);
    CHECK_THAT(out, Catch::Contains("JT1"));
    CHECK_THAT(out, Catch::Contains(".SPEED 20\n"));  // the controller's prompt and echo
    CHECK(sim.status("speed") == "20");

    const std::string text = readFile(record);
    INFO(text);
    CHECK_THAT(text, Catch::Contains("# port: " + sim.valPath()));
    CHECK_THAT(text, Catch::Contains("# config: " + config));
    CHECK_THAT(text, Catch::Contains("\n> WHERE\n< WHERE\\r\\n\n"));
    CHECK_THAT(text, Catch::Contains("\n= lines 4\n> SPEED 20\n"));
    CHECK(robocal::test::replayTranscript(text, "first-day.txt") == 2);
    // What robocal read of WHERE is what the simulator reports.
    const auto joints = numbersAfter(text, "#   = joints");
    std::istringstream status(sim.status("joints_deg"));
    REQUIRE(joints.size() == 6);
    for (double want : joints) {
      std::string v;
      std::getline(status, v, ',');
      CHECK(std::stod(v) == Approx(want).margin(0.006));
    }
  }
  SECTION("a line ~. ends the session: nothing after it is sent") {
    const auto [code, out] = runShell("printf 'SPEED 30\\n~.\\nSPEED 20\\n' | " + term);
    INFO(out);
    CHECK(code == 0);
    CHECK(sim.status("speed") == "30");
    const std::string text = readFile(record);
    CHECK_THAT(text, Catch::Contains("\n> SPEED 30\n< SPEED 30"));  // its reply came first
    CHECK(robocal::test::replayTranscript(text, "first-day.txt") == 1);
    CHECK_THAT(text, !Catch::Contains("SPEED 20"));
  }
  SECTION("errors name the port or the record file") {
    const auto [port_code, port_out] =
        runShell("printf 'WHERE\\n' | " ROBOCAL_BINARY_DIR "/cli/robocal term --config " + config +
                 " --val " + sim.dir() + "/unplugged");
    CHECK(port_code == 1);
    CHECK_THAT(port_out, Catch::Contains(sim.dir() + "/unplugged"));
    const std::string bad = sim.dir() + "/no-such-folder/r.txt";
    const auto [record_code, record_out] =
        runShell("printf 'WHERE\\n' | " ROBOCAL_BINARY_DIR "/cli/robocal term --config " + config +
                 " --val " + sim.valPath() + " --record " + bad);
    CHECK(record_code == 1);
    CHECK_THAT(record_out, Catch::Contains("cannot write the record file " + bad));
    CHECK(sim.status("speed") == "50");
  }
}
