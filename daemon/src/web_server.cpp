#include <robocal/daemon/web_server.hpp>

#include "console_page.hpp"

#include <robocal/daemon/client_hub.hpp>
#include <robocal/proto/protocol.hpp>

#include <spdlog/spdlog.h>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include <chrono>
#include <deque>
#include <optional>

namespace robocal::daemon {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using Clock = std::chrono::steady_clock;

namespace {

constexpr int kMaxHttpConnections = 64;
constexpr std::size_t kMaxRequestBytes = 8 * 1024;
constexpr int kMaxLinesPerMessage = 16;

// The host part of a Host header or an origin's authority: "[::1]:7688" -> "::1",
// "cell7.plant.local:7688" -> "cell7.plant.local".
std::string hostName(std::string authority) {
  if (const auto scheme = authority.find("://"); scheme != std::string::npos)
    authority.erase(0, scheme + 3);
  if (!authority.empty() && authority.front() == '[') {
    const auto end = authority.find(']');
    return authority.substr(1, end == std::string::npos ? std::string::npos : end - 1);
  }
  return authority.substr(0, authority.find(':'));
}

std::chrono::steady_clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

// One HTTP connection: requests read and answered in turn until it closes or upgrades.
struct WebServer::Http {
  explicit Http(tcp::socket socket) : stream(std::move(socket)) {}
  beast::tcp_stream stream;
  beast::flat_buffer buffer;
  std::optional<http::request_parser<http::string_body>> parser;
  std::string peer;
};

// One browser's WebSocket.
struct WebServer::Session {
  explicit Session(tcp::socket socket) : ws(std::move(socket)) {}
  websocket::stream<beast::tcp_stream> ws;
  ClientId id = 0;
  std::string peer;
  beast::flat_buffer in;
  std::deque<std::string> queue;
  std::size_t queued_bytes = 0;
  bool writing = false, watching = false, closed = false;
  Clock::time_point last_progress = Clock::now();
  long dropped = 0;
};

WebServer::WebServer(asio::io_context& io, WebLimits limits, Handlers handlers)
    : io_(io),
      limits_(std::move(limits)),
      handlers_(std::move(handlers)),
      acceptor_(io),
      stall_timer_(io) {}

WebServer::~WebServer() {
  boost::system::error_code ec;
  acceptor_.close(ec);
  try {
    stall_timer_.cancel();
  } catch (const boost::system::system_error&) {
  }
  for (auto& [id, s] : sessions_) beast::get_lowest_layer(s->ws).socket().close(ec);
}

unsigned short WebServer::listen(const std::string& address, unsigned short port) {
  bindAndListen(acceptor_, address, port);
  accept();
  checkStalls();
  return acceptor_.local_endpoint().port();
}

void WebServer::accept() {
  acceptor_.async_accept([this](const boost::system::error_code& ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted) return;
    if (!ec) {
      if (http_open_ >= kMaxHttpConnections) {
        if (counts_.http_refused++ % 100 == 0)
          spdlog::warn(
              "web port: {} HTTP connections open, the limit: refusing new ones until "
              "some end (each within request_timeout_s); {} refused so far",
              kMaxHttpConnections, counts_.http_refused);
        boost::system::error_code ignored;
        socket.close(ignored);
      } else {
        configureClientSocket(socket, limits_.unsent_max_bytes);
        auto h = std::make_shared<Http>(std::move(socket));
        boost::system::error_code peer_ec;
        const auto remote = h->stream.socket().remote_endpoint(peer_ec);
        h->peer =
            peer_ec ? "?" : remote.address().to_string() + ":" + std::to_string(remote.port());
        ++http_open_;
        readRequest(h);
      }
    }
    accept();
  });
}

void WebServer::readRequest(const std::shared_ptr<Http>& h) {
  h->parser.emplace();
  h->parser->header_limit(kMaxRequestBytes);
  h->parser->body_limit(kMaxRequestBytes);
  h->stream.expires_after(seconds(limits_.request_timeout_s));
  http::async_read(h->stream, h->buffer, *h->parser,
                   [this, h](const beast::error_code& ec, std::size_t) {
                     if (ec) {  // closed, timed out, or not HTTP: the connection ends
                       boost::system::error_code ignored;
                       h->stream.socket().shutdown(tcp::socket::shutdown_both, ignored);
                       --http_open_;
                       return;
                     }
                     const auto& req = h->parser->get();
                     if (!hostAllowed(std::string(req[http::field::host]))) return respond(h);
                     if (websocket::is_upgrade(req) && req.target() == "/ws")
                       upgrade(h);
                     else
                       respond(h);
                   });
}

void WebServer::respond(const std::shared_ptr<Http>& h) {
  const auto& req = h->parser->get();
  auto res = std::make_shared<http::response<http::string_body>>();
  res->version(req.version());
  res->keep_alive(req.keep_alive());
  res->set(http::field::server, "robocald");
  res->set(http::field::cache_control, "no-store");
  res->set("X-Content-Type-Options", "nosniff");
  const std::string target(req.target());
  auto answer = [&](http::status status, const char* type, std::string body) {
    res->result(status);
    res->set(http::field::content_type, type);
    res->body() = std::move(body);
  };
  const std::string host(req[http::field::host]);
  if (!hostAllowed(host)) {
    answer(http::status::misdirected_request, "text/plain; charset=utf-8",
           "Host \"" + host +
               "\" is not this cell's: use its address, or list the name in web_allowed_origins\n");
    res->keep_alive(false);
  } else if (req.method() != http::verb::get && req.method() != http::verb::head) {
    answer(http::status::method_not_allowed, "text/plain; charset=utf-8",
           "robocald's web port serves GET only; actions go over the WebSocket (/ws)\n");
    res->set(http::field::allow, "GET, HEAD");
  } else if (target == "/" || target == "/index.html") {
    answer(http::status::ok, "text/html; charset=utf-8", kConsoleHtml);
    // The page's own script and style only; nothing is fetched from elsewhere.
    res->set("Content-Security-Policy",
             "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
             "img-src 'self' data:; connect-src 'self'; base-uri 'none'; form-action 'none'; "
             "frame-ancestors 'none'");
  } else if (target == "/metrics") {
    answer(http::status::ok, "text/plain; version=0.0.4; charset=utf-8", handlers_.metrics());
  } else if (target == "/console.json") {
    answer(http::status::ok, "application/json", proto::frame(handlers_.settings()));
  } else {
    answer(http::status::not_found, "text/plain; charset=utf-8",
           "not found: " + target + " (robocald serves /, /metrics, /console.json and /ws)\n");
  }
  const bool head = req.method() == http::verb::head;
  res->prepare_payload();
  if (head) res->body().clear();  // the length of the GET, no body
  h->stream.expires_after(seconds(limits_.stall_s));
  http::async_write(h->stream, *res, [this, h, res](const beast::error_code& ec, std::size_t) {
    if (ec || !res->keep_alive()) {
      boost::system::error_code ignored;
      h->stream.socket().shutdown(tcp::socket::shutdown_both, ignored);
      --http_open_;
      return;
    }
    readRequest(h);
  });
}

bool WebServer::hostAllowed(const std::string& host) const {
  const std::string name = hostName(host);
  boost::system::error_code ec;
  asio::ip::make_address(name, ec);
  if (!ec || name == "localhost") return true;  // an address: no name to rebind
  for (const std::string& o : limits_.allowed_origins)
    if (hostName(o) == name) return true;
  return false;
}

bool WebServer::originAllowed(const std::string& origin, const std::string& host) const {
  if (origin.empty()) return true;  // not a browser: as good as a TCP client
  if (origin == "http://" + host) return true;
  for (const std::string& o : limits_.allowed_origins)
    if (origin == o) return true;
  return false;
}

void WebServer::upgrade(const std::shared_ptr<Http>& h) {
  const auto& req = h->parser->get();
  const std::string origin(req[http::field::origin]), host(req[http::field::host]);
  auto refuse = [&](http::status status, const std::string& why) {
    ++counts_.refused;
    spdlog::warn("browser {}: WebSocket refused: {}", h->peer, why);
    auto res = std::make_shared<http::response<http::string_body>>(status, req.version());
    res->set(http::field::content_type, "text/plain; charset=utf-8");
    res->body() = why + "\n";
    res->keep_alive(false);
    res->prepare_payload();
    http::async_write(h->stream, *res, [this, h, res](const beast::error_code&, std::size_t) {
      boost::system::error_code ignored;
      h->stream.socket().shutdown(tcp::socket::shutdown_both, ignored);
      --http_open_;
    });
  };
  if (!originAllowed(origin, host))
    return refuse(http::status::forbidden, "origin " + origin + " is not this console's (" + host +
                                               ") nor in web_allowed_origins");
  if (static_cast<int>(sessions_.size()) + handshaking_ >= limits_.max_browsers)
    return refuse(http::status::service_unavailable,
                  "too many browsers (max_browsers " + std::to_string(limits_.max_browsers) + ")");
  --http_open_;  // from here a WebSocket
  ++handshaking_;
  h->stream.expires_never();
  auto s = std::make_shared<Session>(h->stream.release_socket());
  s->peer = h->peer;
  s->ws.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
  s->ws.read_message_max(limits_.max_message_bytes);
  s->ws.text(true);
  // The request is kept alive by the parser in h until the handshake completes.
  s->ws.async_accept(req, [this, h, s](const beast::error_code& ec) {
    --handshaking_;
    if (ec) {
      spdlog::info("browser {}: WebSocket handshake failed: {}", s->peer, ec.message());
      return;
    }
    s->id = next_id_++;
    sessions_[s->id] = s;
    spdlog::info("browser {} connected ({}) ({} open)", s->id, s->peer, sessions_.size());
    if (handlers_.greeting) enqueue(s, proto::frame(handlers_.greeting()), false);
    read(s);
  });
}

void WebServer::read(const std::shared_ptr<Session>& s) {
  s->ws.async_read(s->in, [this, s](const beast::error_code& ec, std::size_t) {
    if (s->closed) return;
    if (ec) {
      close(s, ec == websocket::error::closed ? "closed by the browser" : ec.message());
      return;
    }
    std::string text = beast::buffers_to_string(s->in.data());
    s->in.consume(s->in.size());
    // One message, one or more request lines (the TCP framing, for clients that reuse it).
    int lines = 0;
    std::size_t start = 0;
    while (start < text.size()) {
      std::size_t end = text.find('\n', start);
      if (end == std::string::npos) end = text.size();
      std::string line = text.substr(start, end - start);
      start = end + 1;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.empty()) continue;
      if (++lines > kMaxLinesPerMessage) {
        enqueue(s,
                proto::frame(proto::errorObject("at most " + std::to_string(kMaxLinesPerMessage) +
                                                " request lines per message: the rest is dropped")),
                false);
        break;
      }
      handlers_.on_line(s->id, line);
      if (s->closed) return;
    }
    read(s);
  });
}

void WebServer::send(ClientId browser, const nlohmann::json& object) {
  const auto it = sessions_.find(browser);
  if (it != sessions_.end()) enqueue(it->second, proto::frame(object), false);
}

bool WebServer::anyWatching() const {
  for (const auto& [id, s] : sessions_)
    if (s->watching) return true;
  return false;
}

void WebServer::broadcast(const std::string& line, bool droppable) {
  // Copy: enqueue may close (and erase) a browser.
  std::vector<std::shared_ptr<Session>> targets;
  for (const auto& [id, s] : sessions_)
    if (s->watching) targets.push_back(s);
  for (const auto& s : targets) enqueue(s, line, droppable);
}

void WebServer::setWatching(ClientId browser, bool watching) {
  const auto it = sessions_.find(browser);
  if (it != sessions_.end()) it->second->watching = watching;
}

void WebServer::enqueue(const std::shared_ptr<Session>& s, std::string text, bool droppable) {
  if (s->closed) return;
  if (s->queue.size() >= limits_.queue_max ||
      s->queued_bytes + text.size() > limits_.queue_max_bytes) {
    if (droppable) {
      ++s->dropped;
      ++counts_.dropped_lines;
      return;
    }
    ++counts_.stalled;
    close(s, "its queue is full (" + std::to_string(limits_.queue_max) + " messages)");
    return;
  }
  s->queued_bytes += text.size();
  s->queue.push_back(std::move(text));
  if (!s->writing) {
    s->last_progress = Clock::now();  // the stall clock starts with the write
    write(s);
  }
}

void WebServer::write(const std::shared_ptr<Session>& s) {
  s->writing = true;
  // A deque keeps its front where it is while others are pushed behind it.
  s->ws.async_write(asio::buffer(s->queue.front()),
                    [this, s](const beast::error_code& ec, std::size_t) {
                      if (s->closed) return;
                      if (ec) return close(s, ec.message());
                      s->last_progress = Clock::now();
                      s->queued_bytes -= s->queue.front().size();
                      s->queue.pop_front();
                      if (s->queue.empty())
                        s->writing = false;
                      else
                        write(s);
                    });
}

void WebServer::close(std::shared_ptr<Session> s, const std::string& why) {
  if (s->closed) return;
  s->closed = true;
  boost::system::error_code ignored;
  beast::get_lowest_layer(s->ws).socket().close(ignored);  // pending operations end with errors
  sessions_.erase(s->id);
  spdlog::info("browser {} gone ({}){}", s->id, why,
               s->dropped ? ", " + std::to_string(s->dropped) + " readings dropped" : "");
}

void WebServer::checkStalls() {
  const auto now = Clock::now();
  std::vector<std::shared_ptr<Session>> stuck;
  for (auto& [id, s] : sessions_)
    if (s->writing && now - s->last_progress > seconds(limits_.stall_s)) stuck.push_back(s);
  for (auto& s : stuck) {
    ++counts_.stalled;
    close(s, "stuck: nothing taken for " + std::to_string(limits_.stall_s) + " s");
  }
  stall_timer_.expires_after(std::chrono::seconds(1));
  stall_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) checkStalls();
  });
}

}  // namespace robocal::daemon
