// What `robocal probe` tells a technician, against robocal-cellsim over real ptys: the verdicts
// of the diagnose functions, and the command itself.
#include "cellsim_process.hpp"

#include <robocal/drivers/diagnose.hpp>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <sys/wait.h>

#include <cstdio>
#include <fstream>

using namespace robocal::drivers;
using robocal::test::CellSimProcess;

namespace {
std::pair<int, std::string> runRobocal(const std::string& args) {
  return robocal::test::runShell(std::string(ROBOCAL_BINARY_DIR "/cli/robocal ") + args);
}
}  // namespace

TEST_CASE("Probe: verdicts in technician words", "[drivers][probe]") {
  CellSimProcess sim({"--bar-garbage-every", "5"});
  auto config = sim.driversConfig();
  config.val.connect_timeout_s = 0.5;
  config.bar.stale_after_s = 0.6;
  config.bar.poll_timeout_s = 0.2;
  boost::asio::io_context io;

  SECTION("both answer") {
    const Diagnosis v = diagnoseVal(io, config.val);
    CHECK(v.verdict == Verdict::kOk);
    REQUIRE(v.where);
    CHECK(v.where->joints_deg[1] == Approx(45).margin(0.01));
    int readings = 0;
    const Diagnosis b = diagnoseBar(io, config.bar, 0.3, [&](const BarReading&) { ++readings; });
    CHECK(b.verdict == Verdict::kOk);
    CHECK(readings >= 1);
  }
  SECTION("no port") {
    config.val.serial.path = sim.dir() + "/unplugged";
    const Diagnosis v = diagnoseVal(io, config.val);
    CHECK(v.verdict == Verdict::kNoPort);
    CHECK_THAT(v.message, Catch::Contains("plugged in"));
  }
  SECTION("wrong baud on the controller") {
    config.val.serial.baud = 19200;
    const Diagnosis v = diagnoseVal(io, config.val);
    CHECK(v.verdict == Verdict::kGarbled);
    CHECK_THAT(v.message, Catch::Contains("baud"));
  }
  SECTION("wrong prompt") {
    config.val.prompt = {">"};
    const Diagnosis v = diagnoseVal(io, config.val);
    CHECK(v.verdict == Verdict::kUnparseable);
    CHECK_THAT(v.message, Catch::Contains("val.prompt"));
  }
  SECTION("WHERE headers that do not fit") {
    config.val.joint_headers = {"J1", "J2", "J3", "J4", "J5", "J6"};
    const Diagnosis v = diagnoseVal(io, config.val);
    CHECK(v.verdict == Verdict::kUnparseable);
    CHECK_THAT(v.message, Catch::Contains("val.joint_headers"));
  }
  SECTION("a bar format that does not fit") {
    config.bar.format = "gn";
    const Diagnosis b = diagnoseBar(io, config.bar, 0.2);
    CHECK(b.verdict == Verdict::kUnparseable);
    CHECK_THAT(b.message, Catch::Contains("bar.format"));
  }
  SECTION("a silent bar reader") {
    REQUIRE(sim.control("fault stall bar 5").rfind("ok", 0) == 0);
    const Diagnosis b = diagnoseBar(io, config.bar, 0.2);
    CHECK(b.verdict == Verdict::kNoAnswer);
  }
  SECTION("no probe") {
    REQUIRE(sim.control("fault noprobe").rfind("ok", 0) == 0);
    const Diagnosis b = diagnoseBar(io, config.bar, 0.2);
    CHECK(b.verdict == Verdict::kDeviceError);
    CHECK_THAT(b.message, Catch::Contains("LVDT cable"));
  }
}

TEST_CASE("Probe: the robocal probe command", "[drivers][probe][cli]") {
  CellSimProcess sim;
  const auto [ok_code, ok_out] =
      runRobocal("probe --config " ROBOCAL_SOURCE_DIR "/config/drivers.json --val " +
                 sim.valPath() + " --bar " + sim.barPath() + " --seconds 0.3");
  INFO(ok_out);
  CHECK(ok_code == 0);
  CHECK_THAT(ok_out, Catch::Contains("joints (deg)"));
  CHECK_THAT(ok_out, Catch::Contains(" mm "));

  const auto [bad_code, bad_out] = runRobocal("probe --val " + sim.valPath() + " --val-baud 4800");
  INFO(bad_out);
  CHECK(bad_code == 1);
  CHECK_THAT(bad_out, Catch::Contains("garbled"));
}

TEST_CASE("Probe: the robocal probe command reads robocald's config file",
          "[drivers][probe][cli]") {
  CellSimProcess sim;
  // robocald.json as installed, with its drivers section pointed at the simulator: probe reads
  // that section (the daemon's other keys, unknown to a drivers file, are no error) and probes
  // the ports it names.
  std::ifstream shipped(ROBOCAL_SOURCE_DIR "/config/robocald.json");
  nlohmann::json config = nlohmann::json::parse(shipped);
  config["drivers"] = toJson(sim.driversConfig());
  const std::string path = sim.dir() + "/robocald.json";
  std::ofstream(path) << config.dump(2);
  const auto [code, out] = runRobocal("probe --config " + path + " --seconds 0.3");
  INFO(out);
  CHECK(code == 0);
  CHECK_THAT(out, Catch::Contains("Drivers config: " + path));
  CHECK_THAT(out, Catch::Contains("VAL II controller on " + sim.valPath()));
  CHECK_THAT(out, Catch::Contains("joints (deg)"));
  CHECK_THAT(out, Catch::Contains(" mm "));
}

TEST_CASE("Probe: the bring-up move test in each dialect preset, switched in the shipped config",
          "[drivers][probe][cli]") {
  struct Case {
    std::string dialect;
    std::vector<std::string> sim_args;
    std::string expect;
  };
  for (const Case& c : {Case{"val2", {}, "before the motion ends, showing '*'"},
                        Case{"val2", {"--val-sync-moves"}, "when the motion ends (synchronous)"},
                        Case{"vplus", {}, "before the motion ends"},
                        Case{"kawasaki-as", {}, "completion line(s) were dropped"}}) {
    DYNAMIC_SECTION(c.dialect << (c.sim_args.empty() ? "" : " " + c.sim_args[0])) {
      std::vector<std::string> args{"--time-scale", "2"};  // 2 deg at SPEED 10: 0.17 s
      args.insert(args.end(), c.sim_args.begin(), c.sim_args.end());
      CellSimProcess sim(args, R"({"val": {"dialect": ")" + c.dialect + R"("}})");
      // The shipped config/drivers.json with its dialect switched and its ports pointed at the
      // simulator, nothing else: the preset must carry the rest.
      std::ifstream shipped(ROBOCAL_SOURCE_DIR "/config/drivers.json");
      nlohmann::json edited = nlohmann::json::parse(shipped);
      edited["val"]["dialect"] = c.dialect;
      edited["val"]["serial"]["path"] = sim.valPath();
      edited["bar"]["serial"] = {{"path", sim.barPath()}};
      const std::string config = sim.dir() + "/drivers.json";
      std::ofstream(config) << edited.dump(2);

      // Without the confirmation nothing is sent: the arm does not move.
      const auto [refused_code, refused_out] =
          runRobocal("probe --config " + config + " --move-test 2");
      INFO(refused_out);
      CHECK(refused_code != 0);
      CHECK_THAT(refused_out, Catch::Contains("--i-have-cleared-the-cell"));
      CHECK(sim.status("speed") == "50");  // not even SPEED 10 was sent

      const auto [code, out] = runRobocal("probe --config " + config +
                                          " --move-test 2 --i-have-cleared-the-cell --model " +
                                          ROBOCAL_SOURCE_DIR "/config/puma560-paper.json");
      INFO(out);
      CHECK(code == 0);
      for (int j = 1; j <= 6; ++j)
        CHECK_THAT(out, Catch::Contains("joint " + std::to_string(j) + ": 2.000 deg and back"));
      CHECK_THAT(out, Catch::Contains("WHERE round trip: median"));
      CHECK_THAT(out, Catch::Contains("the " + c.dialect + " dialect drives this controller"));
      CHECK_THAT(out, Catch::Contains(c.expect));
      CHECK(sim.status("speed") == "10");
      CHECK(sim.status("joints_deg") == "0.000,45.000,-90.000,0.000,45.000,0.000");  // back
    }
  }
}
