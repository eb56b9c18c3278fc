// robocald over real TCP: the banner, bad requests, limits, tokens, many and stuck clients.
#include <catch2/catch.hpp>

#include "../drivers/cellsim_process.hpp"
#include "daemon_process.hpp"

#include <robocal/build_info.hpp>
#include <robocal/daemon/token.hpp>
#include <robocal/drivers/config.hpp>

#include <grp.h>
#include <sys/stat.h>
#include <fstream>
#include <thread>

using namespace robocal;
using namespace robocal::test;
using Catch::Matchers::Contains;
using json = nlohmann::json;

namespace {

json daemonConfig(const CellSimProcess& cell, const std::string& dir, int max_clients = 16) {
  std::ofstream(dir + "/cell.json") << smallCell({"B1C1", "B2C2", "B3C3"}, {0}).dump(1);
  json drivers = drivers::toJson(cell.driversConfig());
  drivers["bar"]["mode"] = "streamed";
  return {{"model", ROBOCAL_SOURCE_DIR "/config/puma560-paper.json"},
          {"cell", dir + "/cell.json"},
          {"max_clients", max_clients},
          {"max_line_bytes", 1024},
          {"client_queue_max", 64},
          {"client_stall_s", 1.0},
          {"request_timeout_s", 1.0},
          {"drivers", drivers}};
}

struct Fixture {
  CellSimProcess cell{{"--bar-mode", "streamed", "--stream-hz", "100", "--bar-mm", "150"}};
  std::unique_ptr<DaemonProcess> daemon;
  explicit Fixture(int max_clients = 16) {
    daemon = std::make_unique<DaemonProcess>(daemonConfig(cell, cell.dir(), max_clients));
    daemon->start();
  }
};

}  // namespace

TEST_CASE("robocald greets with VERSION and answers status, runs and result") {
  Fixture f;
  auto c = f.daemon->client();
  CHECK(c->version()["class"] == "VERSION");
  CHECK(c->version()["proto_major"] == 1);
  CHECK(c->version()["release"] == build::kVersion);  // the project's version, from CMake
  const json s = c->request({{"cmd", "status"}});
  CHECK(s["class"] == "STATUS");
  CHECK(s["state"] == "idle");
  CHECK(c->request({{"cmd", "runs"}})["class"] == "RUNS");
  CHECK(c->request({{"cmd", "result"}})["class"] == "RESULT");
}

TEST_CASE("bad requests get an ERROR and the connection lives on") {
  Fixture f;
  auto c = f.daemon->client();
  c->sendRaw("this is not json\n");
  auto e = c->read(5);
  REQUIRE(e);
  CHECK((*e)["class"] == "ERROR");
  CHECK_THAT((*e)["message"].get<std::string>(), Contains("not valid JSON"));
  CHECK(c->request({{"cmd", "jump"}})["message"].get<std::string>().find("unknown cmd") !=
        std::string::npos);
  CHECK(c->request({{"cmd", "watch"}, {"enable", 7}})["class"] == "ERROR");
  CHECK(c->request({{"nocmd", 1}})["class"] == "ERROR");
  // A line past max_line_bytes (1024 here) is dropped whole, with an ERROR, not a disconnect.
  c->sendRaw("{\"cmd\":\"status\",\"pad\":\"" + std::string(100000, 'x') + "\"}\n");
  e = c->read(5);
  REQUIRE(e);
  CHECK((*e)["class"] == "ERROR");
  CHECK_THAT((*e)["message"].get<std::string>(), Contains("longer than 1024 bytes"));
  c->sendRaw(std::string("\xff\xfe\x00garbage\n", 11));
  CHECK(c->read(5).value()["class"] == "ERROR");
  CHECK(c->request({{"cmd", "status"}})["class"] == "STATUS");
}

TEST_CASE("commands that move the robot need the token") {
  Fixture f;
  auto c = f.daemon->client();
  for (const char* cmd : {"start", "confirm", "pause", "resume", "abort", "plan"}) {
    const json e = c->request({{"cmd", cmd}});
    CHECK(e["class"] == "ERROR");
    CHECK_THAT(e["message"].get<std::string>(), Contains("needs the token"));
    CHECK(c->request({{"cmd", cmd}, {"token", "wrong-token-wrong-token"}})["message"] ==
          std::string("wrong token for ") + cmd);
  }
  // The token file is private to the daemon's user, or readable by the operators' group only.
  struct stat st {};
  REQUIRE(::stat((f.daemon->dataDir() + "/token").c_str(), &st) == 0);
  CHECK((st.st_mode & 037) == 0);
  if (st.st_mode & 040) {
    const group* operators = ::getgrnam(daemon::kOperatorGroup);
    REQUIRE(operators);
    CHECK(st.st_gid == operators->gr_gid);
  }
  // With the token, a command is served (nothing to confirm now).
  const json ok = c->request({{"cmd", "confirm"}, {"token", f.daemon->token()}});
  CHECK_THAT(ok["message"].get<std::string>(), Contains("nothing to confirm"));
}

TEST_CASE("many clients: past max_clients new ones are refused, the others are served") {
  Fixture f(8);
  std::vector<std::unique_ptr<proto::Client>> clients;
  for (int i = 0; i < 8; ++i) clients.push_back(f.daemon->client());
  int refused = 0;
  for (int i = 0; i < 3; ++i) {
    try {
      f.daemon->client();
    } catch (const proto::ClientError& e) {
      ++refused;
    }
  }
  CHECK(refused == 3);
  for (auto& c : clients) CHECK(c->request({{"cmd", "status"}})["class"] == "STATUS");
  CHECK(clients[0]->request({{"cmd", "status"}})["client_counts"]["refused"] == 3);
}

TEST_CASE("a client that leaves a request line unfinished is disconnected, the others go on") {
  Fixture f;
  auto slow = f.daemon->client();
  auto other = f.daemon->client();
  // One byte every 0.3 s: never a whole line, past request_timeout_s (1 s here).
  const std::string partial = R"({"cmd":"status")";
  bool closed = false;
  for (std::size_t i = 0; i < partial.size() && !closed; ++i) {
    try {
      slow->sendRaw(partial.substr(i, 1));
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
    } catch (const proto::ClientError&) {
      closed = true;
    }
  }
  // Closed: the rest of the line and a request get no answer.
  bool answered = false;
  try {
    slow->sendRaw("}\n");
    answered = slow->read(2.0).has_value();
  } catch (const proto::ClientError&) {
  }
  CHECK_FALSE(answered);
  const json s = other->request({{"cmd", "status"}});
  CHECK(s["client_counts"]["timed_out"] == 1);
  CHECK(s["clients"] == 1);
  // A line sent whole, however slowly the client thinks between lines, is served.
  auto patient = f.daemon->client();
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  CHECK(patient->request({{"cmd", "status"}})["class"] == "STATUS");
}

TEST_CASE("a watcher that never reads changes nothing for the others") {
  Fixture f;
  auto stuck = f.daemon->client();
  stuck->send({{"cmd", "watch"}, {"enable", true}});  // and never reads again
  auto watcher = f.daemon->client();
  watcher->send({{"cmd", "watch"}, {"enable", true}});
  // The bar streams at 100 readings/s; the live watcher sees readings throughout.
  int bars = 0;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(4);
  while (std::chrono::steady_clock::now() < until)
    if (auto o = watcher->read(0.5); o && (*o)["class"] == "BAR") ++bars;
  CHECK(bars > 100);
  CHECK(watcher->request({{"cmd", "status"}}, 10, "STATUS")["class"] == "STATUS");
  CHECK(f.daemon->running());
}
