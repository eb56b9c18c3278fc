// robocal-cellsim's stdin control channel (the socket one is used by every other test).
#include <catch2/catch.hpp>

#include <robocal/build_info.hpp>

#include <cstdio>
#include <string>

TEST_CASE("Cellsim: control commands on stdin, replies on stdout", "[drivers][cellsim]") {
  const std::string cmd = "printf 'status\\nconnect B9C1\\nevents\\nquit\\n' | " ROBOCAL_BINARY_DIR
                          "/sim/cellsim/robocal-cellsim --model " ROBOCAL_SOURCE_DIR
                          "/config/puma560-paper.json --stdin-control 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  REQUIRE(p);
  std::string out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  CHECK(::pclose(p) == 0);
  INFO(out);
  CHECK_THAT(out, Catch::Contains("\nready\n"));
  CHECK_THAT(out, Catch::Contains("ok joints_deg=0.000,45.000,-90.000"));
  CHECK_THAT(out, Catch::Contains("error: "));  // there is no ball 9
  CHECK_THAT(out, Catch::Contains("ok 0\n"));
  CHECK_THAT(out, Catch::Contains("ok bye"));
}

TEST_CASE("Cellsim: --version says the project's version, as robocal and robocald do",
          "[drivers][cellsim]") {
  FILE* p = ::popen(ROBOCAL_BINARY_DIR "/sim/cellsim/robocal-cellsim --version 2>&1", "r");
  REQUIRE(p);
  std::string out;
  char buf[256];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  CHECK(::pclose(p) == 0);
  CHECK(out == std::string("robocal-cellsim ") + robocal::build::kVersion + "\n");
}
