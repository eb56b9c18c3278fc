// The browser side of robocald (docs/console.md): one HTTP port (web_port; loopback by default,
// like the TCP port) on the daemon's event loop, serving
//   GET /              the operator's console, one page with every asset compiled in
//   GET /console.json  what the page needs besides the protocol (the bar's limits)
//   GET /metrics       the Prometheus text format
//   GET /ws            a WebSocket: the TCP protocol's requests and objects, one JSON object per
//                      text message (a message may also hold up to 16 request lines)
// Everything is readable without the token; actions carry it in their JSON, as on TCP.
// Bounded as the TCP side is: at most max_browsers WebSockets, a bounded queue each (BAR
// readings dropped first), a browser whose queue does not move for stall_s is closed, a request
// not read within request_timeout_s is dropped. Nothing a browser does blocks the loop.
#pragma once

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace robocal::daemon {

struct WebLimits {
  int max_browsers = 32;
  std::size_t max_message_bytes = 16 * 1024;
  std::size_t queue_max = 4096;
  double stall_s = 5.0;
  double request_timeout_s = 10.0;
  // Origins besides the page's own (http://HOST:PORT as the browser reached it) whose pages may
  // open the WebSocket, e.g. "http://cell7-console.plant.local:7688". Their host names are also
  // the names, besides IP addresses and localhost, a request's Host may carry (a page of another
  // site that rebinds its name to this address is refused).
  std::vector<std::string> allowed_origins;
  std::size_t queue_max_bytes = 8 * 1024 * 1024;  // per browser, besides queue_max messages
  // As the TCP clients' (HubLimits): without it a browser that stopped reading was closed only
  // by the WebSocket's own 300 s timeout, its queue at megabytes, not after stall_s.
  int unsent_max_bytes = 16 * 1024;
};

struct WebCounts {
  long refused = 0;        // over max_browsers, or a foreign origin
  long stalled = 0;        // closed as stuck
  long dropped_lines = 0;  // BAR readings not sent to slow browsers
  // HTTP connections closed at once because kMaxHttpConnections (64) were open, requests
  // unfinished (each is closed after request_timeout_s): page and /metrics alike.
  long http_refused = 0;
};

class WebServer {
 public:
  using ClientId = std::uint64_t;
  // Browser ids start here, TCP clients' ids below: one id space for the daemon's replies.
  static constexpr ClientId kFirstId = ClientId{1} << 40;
  static bool owns(ClientId id) { return id >= kFirstId; }

  struct Handlers {
    std::function<void(ClientId, const std::string& line)> on_line;  // each request line
    std::function<nlohmann::json()> greeting;                        // VERSION, on open
    std::function<std::string()> metrics;                            // /metrics
    std::function<nlohmann::json()> settings;                        // /console.json
  };

  WebServer(boost::asio::io_context& io, WebLimits limits, Handlers handlers);
  ~WebServer();
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  // Binds and listens; returns the bound port (0: any free one). Throws on failure.
  unsigned short listen(const std::string& address, unsigned short port);

  void send(ClientId browser, const nlohmann::json& object);
  // To every watching browser: `line` as proto::frame made it (the TCP bytes, newline included).
  void broadcast(const std::string& line, bool droppable);
  bool anyWatching() const;
  void setWatching(ClientId browser, bool watching);
  int browserCount() const { return static_cast<int>(sessions_.size()); }
  WebCounts counts() const { return counts_; }

 private:
  struct Http;
  struct Session;
  void accept();
  void readRequest(const std::shared_ptr<Http>& h);
  void respond(const std::shared_ptr<Http>& h);
  void upgrade(const std::shared_ptr<Http>& h);
  void read(const std::shared_ptr<Session>& s);
  void enqueue(const std::shared_ptr<Session>& s, std::string text, bool droppable);
  void write(const std::shared_ptr<Session>& s);
  // By value: the map's own pointer may be what is erased.
  void close(std::shared_ptr<Session> s, const std::string& why);
  void checkStalls();
  bool hostAllowed(const std::string& host) const;
  bool originAllowed(const std::string& origin, const std::string& host) const;

  boost::asio::io_context& io_;
  WebLimits limits_;
  Handlers handlers_;
  boost::asio::ip::tcp::acceptor acceptor_;
  boost::asio::steady_timer stall_timer_;
  std::map<ClientId, std::shared_ptr<Session>> sessions_;
  int http_open_ = 0;    // plain HTTP connections being served
  int handshaking_ = 0;  // WebSockets accepted, handshake not yet done: they count as browsers
  ClientId next_id_ = kFirstId;
  WebCounts counts_;
};

}  // namespace robocal::daemon
