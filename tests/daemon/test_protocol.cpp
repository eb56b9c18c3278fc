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

TEST_CASE("models, activate and compensate requests are validated field by field") {
  CHECK(parseRequest(R"({"cmd":"models"})").cmd == Cmd::kModels);
  CHECK(parseRequest(R"({"cmd":"activate","version":4})").model_version == 4);
  CHECK_THROWS_WITH(parseRequest(R"({"cmd":"activate"})"), Contains("activate needs \"version\""));
  const Request r =
      parseRequest(R"({"cmd":"compensate","targets":[{"name":"a","pose_mm_deg":[1,2,3,4,5,6]},)"
                   R"({"joints_deg":[0,10,20,30,40,50]}],"tool_mm_deg":[0,0,100,0,0,0]})");
  REQUIRE(r.targets.size() == 2);
  CHECK(r.targets[0].name == "a");
  CHECK((*r.targets[0].pose_mm_deg)[2] == 3);
  CHECK_FALSE(r.targets[0].joints_deg);
  CHECK((*r.targets[1].joints_deg)[5] == 50);
  CHECK((*r.tool_mm_deg)[2] == 100);
  CHECK_THROWS_WITH(parseRequest(R"({"cmd":"compensate"})"), Contains("compensate needs"));
  CHECK_THROWS_WITH(parseRequest(R"({"cmd":"compensate","targets":[{"pose_mm_deg":[1,2,3]}]})"),
                    Contains("targets[0].pose_mm_deg must be an array of 6 numbers"));
  CHECK_THROWS_WITH(
      parseRequest(R"({"cmd":"compensate","targets":[{"joints_deg":[1,2,3,4,5,"x"]}]})"),
      Contains("targets[0].joints_deg[5] must be a finite number"));
  CHECK_THROWS_WITH(parseRequest(R"({"cmd":"compensate","targets":[{"name":"x"}]})"),
                    Contains("targets[0] needs one of"));
  std::string many = R"({"cmd":"compensate","targets":[)";
  for (int i = 0; i <= 1000; ++i)
    many += std::string(i ? "," : "") + R"({"joints_deg":[0,0,0,0,0,0]})";
  CHECK_THROWS_WITH(parseRequest(many + "]}"), Contains("at most 1000"));
  CHECK(needsToken(Cmd::kActivate));
  CHECK_FALSE(needsToken(Cmd::kModels));
  CHECK_FALSE(needsToken(Cmd::kCompensate));
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
