// The wire protocol, without sockets.
#include <catch2/catch.hpp>

#include <robocal/proto/protocol.hpp>

using namespace robocal::proto;
using Catch::Matchers::Contains;

TEST_CASE("requests parse with their fields") {
  CHECK(parseRequest(R"({"cmd":"status"})").cmd == Cmd::kStatus);
  const Request w = parseRequest(R"({"cmd":"watch","enable":false})");
  CHECK(w.cmd == Cmd::kWatch);
  CHECK_FALSE(w.watch_enable);
  const Request c = parseRequest(R"({"cmd":"confirm","shell":3,"token":"abc"})");
  CHECK(c.shell == 3);
  CHECK(c.token == "abc");
  CHECK(parseRequest(R"({"cmd":"start","plan":"/tmp/p.json"})").plan_path == "/tmp/p.json");
  CHECK(parseRequest(R"({"cmd":"resume","run":"r1"})").run_id == "r1");
}

TEST_CASE("bad requests say what is wrong") {
  CHECK_THROWS_WITH(parseRequest("{"), Contains("not valid JSON"));
  CHECK_THROWS_WITH(parseRequest("[1,2]"), Contains("must be a JSON object, got array"));
  CHECK_THROWS_WITH(parseRequest("{}"), Contains("no \"cmd\""));
  CHECK_THROWS_WITH(parseRequest(R"({"cmd":5})"), Contains("\"cmd\" must be a string"));
  CHECK_THROWS_WITH(parseRequest(R"({"cmd":"fly"})"), Contains("unknown cmd \"fly\""));
  CHECK_THROWS_WITH(parseRequest(R"({"cmd":"watch","enable":"yes"})"),
                    Contains("field 'enable' of watch must be true or false, got string"));
  CHECK_THROWS_WITH(parseRequest(R"({"cmd":"confirm","shell":1.5})"),
                    Contains("field 'shell' of confirm must be a whole number"));
  CHECK_THROWS_WITH(parseRequest(R"({"cmd":"plan","plan":"a","cell":"b"})"), Contains("not both"));
}

TEST_CASE("what needs the token") {
  CHECK_FALSE(needsToken(Cmd::kStatus));
  CHECK_FALSE(needsToken(Cmd::kWatch));
  CHECK_FALSE(needsToken(Cmd::kResult));
  CHECK_FALSE(needsToken(Cmd::kRuns));
  for (Cmd c : {Cmd::kPlan, Cmd::kStart, Cmd::kConfirm, Cmd::kPause, Cmd::kResume, Cmd::kAbort})
    CHECK(needsToken(c));
}

TEST_CASE("server objects are one line with a class") {
  const std::string line = frame(errorObject("bad \xff byte", "start"));
  CHECK(line.back() == '\n');
  CHECK(line.find('\n') == line.size() - 1);
  CHECK_THAT(line, Contains("\"class\":\"ERROR\""));
  CHECK(versionObject("1.2.3")["proto_major"] == kProtoMajor);
}

TEST_CASE("Run states: every wire name parses back, and only a run that owns the robot is busy",
          "[proto]") {
  using robocal::proto::RunState;
  int busy = 0;
  for (int i = 0; i <= static_cast<int>(RunState::kError); ++i) {
    const auto state = static_cast<RunState>(i);
    const std::string name = robocal::proto::runStateName(state);
    INFO(name);
    CHECK(robocal::proto::parseRunState(name) == state);
    busy += robocal::proto::isBusy(state) ? 1 : 0;
  }
  CHECK(busy == 4);
  CHECK_FALSE(robocal::proto::isBusy(RunState::kPaused));
  CHECK_FALSE(robocal::proto::parseRunState("over range"));
}
