// robocald's web port over real TCP (docs/console.md): the page, /metrics, the WebSocket carrying
// the TCP protocol, origin checks, the browser limit, bad HTTP. The page itself in a browser:
// tests/web/console_test.sh.
#include <catch2/catch.hpp>

#include "../drivers/cellsim_process.hpp"
#include "daemon_process.hpp"

#include <robocal/daemon/metrics.hpp>
#include <robocal/drivers/config.hpp>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include <fstream>
#include <thread>

using namespace robocal;
using namespace robocal::test;
using Catch::Matchers::Contains;
using json = nlohmann::json;
namespace asio = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

namespace {

struct WebFixture {
  CellSimProcess cell{{"--bar-mode", "streamed", "--stream-hz", "50", "--bar-mm", "150"}};
  std::unique_ptr<DaemonProcess> daemon;
  WebFixture() {
    std::ofstream(cell.dir() + "/cell.json") << smallCell({"B1C1", "B2C2", "B3C3"}, {0}).dump(1);
    json drivers = drivers::toJson(cell.driversConfig());
    drivers["bar"]["mode"] = "streamed";
    daemon = std::make_unique<DaemonProcess>(
        json{{"model", ROBOCAL_SOURCE_DIR "/config/puma560-paper.json"},
             {"cell", cell.dir() + "/cell.json"},
             {"web_port", 0},
             {"max_browsers", 2},
             {"request_timeout_s", 1.0},
             {"drivers", drivers}});
    daemon->start();
    REQUIRE(daemon->webPort() != 0);
  }
};

// Raw bytes to the web port; everything it answers until it closes the connection.
std::string rawHttp(unsigned short port, const std::string& request) {
  asio::io_context io;
  tcp::socket s(io);
  s.connect({asio::ip::make_address("127.0.0.1"), port});
  asio::write(s, asio::buffer(request));
  std::string reply;
  boost::system::error_code ec;
  asio::read(s, asio::dynamic_buffer(reply), ec);  // to EOF
  return reply;
}

std::string get(unsigned short port, const std::string& target) {
  return rawHttp(port,
                 "GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
}

// A WebSocket client as a browser would be (Origin = the page's own unless given).
struct Browser {
  asio::io_context io;
  websocket::stream<tcp::socket> ws{io};
  // `receive_buffer_bytes`: a small kernel buffer on this side (0: the kernel's), for a browser
  // that stops reading to be seen as one soon.
  Browser(unsigned short port, const std::string& origin = {}, int receive_buffer_bytes = 0) {
    ws.next_layer().open(tcp::v4());
    if (receive_buffer_bytes > 0)
      ws.next_layer().set_option(asio::socket_base::receive_buffer_size(receive_buffer_bytes));
    ws.next_layer().connect({asio::ip::make_address("127.0.0.1"), port});
    const std::string host = "127.0.0.1:" + std::to_string(port);
    const std::string o = origin.empty() ? "http://" + host : origin;
    ws.set_option(websocket::stream_base::decorator(
        [o](websocket::request_type& req) { req.set(beast::http::field::origin, o); }));
    ws.handshake(host, "/ws");
  }
  void send(const json& request) { ws.write(asio::buffer(request.dump())); }
  json read() {
    beast::flat_buffer b;
    ws.read(b);
    return json::parse(beast::buffers_to_string(b.data()));
  }
  // The next object of class `cls` (skipping the stream).
  json readClass(const std::string& cls) {
    for (int i = 0; i < 2000; ++i) {
      json o = read();
      if (o["class"] == cls) return o;
    }
    FAIL("no " << cls << " in 2000 objects");
    return {};
  }
};

}  // namespace

TEST_CASE("web port: the page, /metrics and /console.json over HTTP, and bad requests answered",
          "[web]") {
  WebFixture f;
  const unsigned short port = f.daemon->webPort();
  const std::string page = get(port, "/");
  CHECK_THAT(page, Contains("HTTP/1.1 200") && Contains("text/html") &&
                       Contains("<title>robocal console</title>") &&
                       Contains("Content-Security-Policy"));
  const std::string metrics = get(port, "/metrics");
  CHECK_THAT(metrics, Contains("HTTP/1.1 200") && Contains("text/plain; version=0.0.4") &&
                          Contains("robocal_run_state{state=\"idle\"} 1") &&
                          Contains("# TYPE robocal_samples_total counter") &&
                          Contains("robocal_device_connected{device=\"bar\"} 1"));
  const std::string settings = get(port, "/console.json");
  CHECK_THAT(settings, Contains("\"bar_hard_limit_mm\""));
  CHECK_THAT(get(port, "/etc/passwd"), Contains("HTTP/1.1 404"));
  CHECK_THAT(rawHttp(port,
                     "POST /metrics HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 0\r\n"
                     "Connection: close\r\n\r\n"),
             Contains("HTTP/1.1 405") && Contains("Allow: GET, HEAD"));
  // Not HTTP, a request far too large, a request never finished: each connection ends, the
  // daemon goes on.
  CHECK(rawHttp(port, "HELLO ROBOT\r\n\r\n").find("200 OK") == std::string::npos);
  CHECK(rawHttp(port, "GET / HTTP/1.1\r\nX-Big: " + std::string(20000, 'a') + "\r\n\r\n")
            .find("200 OK") == std::string::npos);
  CHECK(rawHttp(port, "GET / HTTP/1.1\r\nHost: x\r\n").find("200 OK") == std::string::npos);
  CHECK_THAT(get(port, "/metrics"), Contains("HTTP/1.1 200"));
  CHECK(f.daemon->client()->request({{"cmd", "status"}})["state"] == "idle");  // TCP unchanged
  // A name that is not this cell's (a page that rebound its name to this address): refused;
  // addresses and localhost are served.
  CHECK_THAT(rawHttp(port, "GET /metrics HTTP/1.1\r\nHost: evil.example:" + std::to_string(port) +
                               "\r\n\r\n"),
             Contains("HTTP/1.1 421") && Contains("web_allowed_origins"));
  CHECK_THAT(rawHttp(port, "GET / HTTP/1.1\r\nHost: localhost:" + std::to_string(port) +
                               "\r\nConnection: close\r\n\r\n"),
             Contains("HTTP/1.1 200"));
}

TEST_CASE("web port: the WebSocket carries the TCP protocol, and actions need the token", "[web]") {
  WebFixture f;
  const unsigned short port = f.daemon->webPort();
  Browser b(port);
  CHECK(b.read()["class"] == "VERSION");
  b.send({{"cmd", "status"}});
  const json status = b.readClass("STATUS");
  CHECK(status["clients"] == 1);  // the browser counts as a client
  b.send({{"cmd", "confirm"}});
  CHECK_THAT(b.readClass("ERROR")["message"].get<std::string>(), Contains("needs the token"));
  b.send({{"cmd", "pause"}, {"token", "not the token"}});
  CHECK_THAT(b.readClass("ERROR")["message"].get<std::string>(), Contains("wrong token"));
  b.send({{"cmd", "pause"}, {"token", f.daemon->token()}});
  const json no_run = b.read();  // the token is right: refused only as there is no run
  CHECK(no_run["class"] == "ERROR");
  CHECK(no_run["message"].get<std::string>().find("token") == std::string::npos);
  // Several request lines in one message, and bad JSON: answered one by one.
  b.ws.write(asio::buffer(std::string("{\"cmd\":\"runs\"}\nnot json\n")));
  CHECK(b.read()["class"] == "RUNS");
  CHECK(b.read()["class"] == "ERROR");
  // At most 16 request lines in one message: the rest is dropped with an ERROR that says so.
  std::string many;
  for (int i = 0; i < 40; ++i) many += "{\"cmd\":\"status\"}\n";
  b.ws.write(asio::buffer(many));
  for (int i = 0; i < 16; ++i) CHECK(b.read()["class"] == "STATUS");
  CHECK_THAT(b.read()["message"].get<std::string>(), Contains("at most 16 request lines"));
  // Watching: the stream, as on TCP.
  b.send({{"cmd", "watch"}, {"enable", true}});
  CHECK(b.readClass("WATCH")["enable"] == true);
  CHECK(b.readClass("BAR")["kind"] == "reading");
  CHECK(b.readClass("BAR")["seq"].is_number());
  // The same daemon on TCP sees the browser among its clients.
  CHECK(f.daemon->client()->request({{"cmd", "status"}})["clients"] == 2);
}

TEST_CASE("web port: a browser that stops reading is closed after client_stall_s, not 300 s",
          "[web]") {
  WebFixture f;
  const unsigned short port = f.daemon->webPort();
  Browser stuck(port, {}, 2048);
  CHECK(stuck.read()["class"] == "VERSION");
  stuck.send({{"cmd", "watch"}, {"enable", true}});  // 50 readings a second, and never read again
  const auto started = std::chrono::steady_clock::now();
  std::string metrics;
  for (int i = 0; i < 60; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    metrics = get(port, "/metrics");
    if (metrics.find("robocal_client_events_total{transport=\"web\",kind=\"stalled\"} 1") !=
        std::string::npos)
      break;
  }
  const double took_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  INFO(metrics);
  CHECK_THAT(metrics,
             Contains("robocal_client_events_total{transport=\"web\",kind=\"stalled\"} 1"));
  // The kernel's buffers fill in seconds at 16 KiB unsent, then client_stall_s (5 s).
  CHECK(took_s < 25);
  // Another browser is served as before.
  Browser fresh(port);
  CHECK(fresh.read()["class"] == "VERSION");
}

TEST_CASE("web port: a foreign origin and browsers past max_browsers are refused", "[web]") {
  WebFixture f;
  const unsigned short port = f.daemon->webPort();
  CHECK_THROWS(Browser(port, "http://evil.example"));
  Browser one(port), two(port);
  CHECK(one.read()["class"] == "VERSION");
  CHECK(two.read()["class"] == "VERSION");
  CHECK_THROWS(Browser(port));  // max_browsers 2
  one.send({{"cmd", "status"}});
  CHECK(one.readClass("STATUS")["clients"] == 2);
  const std::string metrics = get(port, "/metrics");
  CHECK_THAT(metrics, Contains("robocal_clients{transport=\"web\"} 2"));
}

TEST_CASE("metrics: counters from the published objects, state and result as gauges", "[web]") {
  daemon::Metrics m;
  m.observe({{"class", "BAR"}, {"kind", "reading"}, {"deflection_mm", 0.1}});
  m.observe({{"class", "BAR"}, {"kind", "over_range"}});
  m.observe({{"class", "BAR"}, {"kind", "over_range"}});
  m.observe({{"class", "SAMPLE"}, {"shell", 1}});
  m.observe({{"class", "STATE"}, {"from", "measuring"}, {"to", "paused"}});
  m.observe({{"class", "EVENT"}, {"event", "link_faults"}, {"val_timeouts", 2}, {"shell", 3}});
  m.observe({{"class", "EVENT"}, {"event", "link_faults"}, {"val_timeouts", 1}});
  m.observe({{"class", "EVENT"}, {"event", "recentre"}, {"shell", 3}});
  m.observe("not an object");
  const json status = {{"state", "measuring"},
                       {"points_done", 7},
                       {"points_total", 20},
                       {"clients", 3},
                       {"bar", {{"deflection_mm", -0.25}}},
                       {"devices", {{"val", true}, {"bar", false}}},
                       {"client_counts", {{"refused", 1}, {"stalled", 0}}}};
  const json result = {{"class", "RESULT"},
                       {"rms_mm", 0.03},
                       {"n", 800},
                       {"validation_rms_mm", 0.04},
                       {"work_volume", {{"predicted_position_error_mm", {{"rms", 0.02}}}}}};
  daemon::Metrics::Clients clients;
  clients.tcp = 2;
  clients.web = 1;
  clients.web_counts.refused = 4;
  const std::string text = m.text(status, result, clients);
  CHECK_THAT(text,
             Contains("robocal_run_state{state=\"measuring\"} 1\n") &&
                 Contains("robocal_run_state{state=\"idle\"} 0\n") &&
                 Contains("robocal_points_done 7\n") && Contains("robocal_samples_total 1\n") &&
                 Contains("robocal_bar_over_range_total 2\n") &&
                 Contains("robocal_bar_deflection_meters -0.00025\n") &&
                 Contains("robocal_faults_total{kind=\"val_timeouts\"} 3\n") &&
                 Contains("robocal_run_stops_total{state=\"paused\"} 1\n") &&
                 Contains("robocal_events_total{event=\"recentre\"} 1\n") &&
                 Contains("robocal_device_connected{device=\"bar\"} 0\n") &&
                 Contains("robocal_clients{transport=\"web\"} 1\n") &&
                 Contains("robocal_clients{transport=\"tcp\"} 2\n") &&
                 Contains("robocal_client_events_total{transport=\"tcp\",kind=\"refused\"} 1\n") &&
                 Contains("robocal_client_events_total{transport=\"web\",kind=\"refused\"} 4\n") &&
                 Contains("robocal_fit_rms_meters 3e-05\n") &&
                 Contains("robocal_validation_rms_meters 4e-05\n") &&
                 Contains("robocal_work_volume_error_meters 2e-05\n"));
  CHECK(text.find("shell\"}") == std::string::npos);  // "shell" of an event is not a fault
  // Before any fit: no fit gauges at all (not zeros, which would read as a perfect fit).
  const std::string before = m.text(status, {{"available", false}}, {});
  CHECK(before.find("robocal_fit_rms_meters") == std::string::npos);
}
