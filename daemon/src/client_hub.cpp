#include <robocal/daemon/client_hub.hpp>

#include <robocal/proto/protocol.hpp>

#include <spdlog/spdlog.h>
#include <boost/asio/write.hpp>

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <optional>
#include <vector>

namespace robocal::daemon {

namespace asio = boost::asio;
using tcp = asio::ip::tcp;
using Clock = std::chrono::steady_clock;

struct ClientHub::Client {
  explicit Client(asio::io_context& io) : socket(io) {}
  ClientId id = 0;
  tcp::socket socket;
  std::string peer;
  std::array<char, 4096> buffer{};
  std::string line;
  bool discarding = false;                        // inside a line that was too long
  std::optional<Clock::time_point> line_started;  // the first byte of an unfinished line
  bool watching = false;
  bool writing = false;
  std::size_t front_sent = 0;  // bytes of the first queued line already written
  bool closed = false;
  std::deque<std::string> queue;
  Clock::time_point last_progress = Clock::now();
  long dropped = 0;
};

ClientHub::ClientHub(asio::io_context& io, HubLimits limits, LineHandler on_line,
                     std::function<nlohmann::json()> greeting)
    : io_(io),
      limits_(limits),
      on_line_(std::move(on_line)),
      greeting_(std::move(greeting)),
      acceptor_(io),
      stall_timer_(io) {}

ClientHub::~ClientHub() {
  boost::system::error_code ec;
  acceptor_.close(ec);
  try {
    stall_timer_.cancel();  // may throw (Boost < 1.77); a destructor must not
  } catch (const boost::system::system_error&) {
  }
  for (auto& [id, c] : clients_) c->socket.close(ec);
}

void bindAndListen(tcp::acceptor& acceptor, const std::string& address, unsigned short port) {
  const tcp::endpoint endpoint(asio::ip::make_address(address), port);
  acceptor.open(endpoint.protocol());
  acceptor.set_option(tcp::acceptor::reuse_address(true));
  acceptor.bind(endpoint);
  acceptor.listen();
}

unsigned short ClientHub::listen(const std::string& address, unsigned short port) {
  bindAndListen(acceptor_, address, port);
  accept();
  checkStalls();
  return acceptor_.local_endpoint().port();
}

void ClientHub::accept() {
  auto c = std::make_shared<Client>(io_);
  acceptor_.async_accept(c->socket, [this, c](const boost::system::error_code& ec) {
    if (ec == asio::error::operation_aborted) return;
    if (!ec) {
      boost::system::error_code peer_ec;
      const auto remote = c->socket.remote_endpoint(peer_ec);
      c->peer = peer_ec ? "?" : remote.address().to_string() + ":" + std::to_string(remote.port());
      if (static_cast<int>(clients_.size()) >= limits_.max_clients) {
        ++refused_;
        spdlog::warn("client {} refused: {} clients already connected", c->peer, clients_.size());
        const std::string msg = proto::frame(proto::errorObject(
            "too many clients (" + std::to_string(limits_.max_clients) + "); try again later"));
        boost::system::error_code wec;
        asio::write(c->socket, asio::buffer(msg), wec);
        c->socket.close(wec);
      } else {
        c->id = next_id_++;
        clients_[c->id] = c;
        configureClientSocket(c->socket, limits_.unsent_max_bytes);
        spdlog::info("client {} connected from {}", c->id, c->peer);
        enqueue(c, proto::frame(greeting_()), false);
        read(c);
      }
    } else {
      spdlog::warn("accept failed: {}", ec.message());
    }
    accept();
  });
}

void configureClientSocket(tcp::socket& socket, int unsent_max_bytes) {
  // Lines go out as they come: with Nagle, a line waits while the previous one is unacknowledged,
  // up to the client's delayed ACK (40 ms) when the client is slow to read.
  boost::system::error_code ec;
  socket.set_option(tcp::no_delay(true), ec);
  if (ec) spdlog::warn("TCP_NODELAY: {}", ec.message());
#ifdef TCP_NOTSENT_LOWAT
  if (::setsockopt(socket.native_handle(), IPPROTO_TCP, TCP_NOTSENT_LOWAT, &unsent_max_bytes,
                   sizeof unsent_max_bytes) != 0)
    spdlog::warn("TCP_NOTSENT_LOWAT: {}", std::strerror(errno));
#endif
}

void ClientHub::read(const std::shared_ptr<Client>& c) {
  c->socket.async_read_some(
      asio::buffer(c->buffer), [this, c](const boost::system::error_code& ec, std::size_t n) {
        if (c->closed) return;
        if (ec) {
          close(c, ec == asio::error::eof ? "disconnected" : ec.message());
          return;
        }
        for (std::size_t i = 0; i < n && !c->closed; ++i) {
          const char ch = c->buffer[i];
          if (ch != '\n' && !c->line_started) c->line_started = Clock::now();
          if (ch == '\n') {
            c->line_started.reset();
            if (c->discarding) {
              c->discarding = false;
              enqueue(c,
                      proto::frame(proto::errorObject("request longer than " +
                                                      std::to_string(limits_.max_line_bytes) +
                                                      " bytes, ignored")),
                      false);
            } else {
              std::string line;
              line.swap(c->line);
              if (!line.empty() && line.back() == '\r') line.pop_back();
              if (!line.empty()) on_line_(c->id, line);
            }
          } else if (!c->discarding) {
            c->line.push_back(ch);
            if (c->line.size() > limits_.max_line_bytes) {
              c->line.clear();
              c->line.shrink_to_fit();
              c->discarding = true;
            }
          }
        }
        if (!c->closed) read(c);
      });
}

void ClientHub::send(ClientId id, const nlohmann::json& object) {
  const auto it = clients_.find(id);
  if (it != clients_.end()) enqueue(it->second, proto::frame(object), false);
}

void ClientHub::broadcast(const nlohmann::json& object, bool droppable) {
  if (clients_.empty()) return;
  const std::string line = proto::frame(object);
  // Copy: enqueue may close (and erase) a client.
  std::vector<std::shared_ptr<Client>> targets;
  for (const auto& [id, c] : clients_)
    if (c->watching) targets.push_back(c);
  for (const auto& c : targets) enqueue(c, line, droppable);
}

void ClientHub::setWatching(ClientId id, bool watching) {
  const auto it = clients_.find(id);
  if (it != clients_.end()) it->second->watching = watching;
}

void ClientHub::enqueue(const std::shared_ptr<Client>& c, std::string line, bool droppable) {
  if (c->closed) return;
  if (c->queue.size() >= limits_.queue_max) {
    if (droppable) {
      ++c->dropped;
      ++dropped_lines_;
      return;
    }
    if (c->queue.size() >= 2 * limits_.queue_max) {
      close(c, "send queue full (client does not read)");
      return;
    }
  }
  if (c->queue.empty()) c->last_progress = Clock::now();
  c->queue.push_back(std::move(line));
  if (!c->writing) write(c);
}

void ClientHub::write(const std::shared_ptr<Client>& c) {
  if (c->queue.empty() || c->closed) return;
  c->writing = true;
  // What is queued (up to a limit) in one system call: a client that fell behind catches up with
  // few of them. Whatever the kernel takes counts as progress, even part of a line, so a slow
  // link is not mistaken for a stuck client. Deque elements stay put while lines are pushed.
  constexpr std::size_t kMaxLines = 64, kMaxBytes = 64 * 1024;
  std::vector<asio::const_buffer> buffers;
  std::size_t bytes = 0;
  for (const std::string& line : c->queue) {
    if (buffers.size() == kMaxLines || bytes >= kMaxBytes) break;
    const std::size_t skip = buffers.empty() ? c->front_sent : 0;
    buffers.push_back(asio::buffer(line) + skip);
    bytes += line.size() - skip;
  }
  c->socket.async_write_some(buffers,
                             [this, c](const boost::system::error_code& ec, std::size_t sent) {
                               c->writing = false;
                               if (c->closed) return;
                               if (ec) {
                                 close(c, ec.message());
                                 return;
                               }
                               while (sent > 0) {
                                 const std::size_t left = c->queue.front().size() - c->front_sent;
                                 if (sent < left) {
                                   c->front_sent += sent;
                                   break;
                                 }
                                 sent -= left;
                                 c->queue.pop_front();
                                 c->front_sent = 0;
                               }
                               c->last_progress = Clock::now();
                               write(c);
                             });
}

void ClientHub::close(std::shared_ptr<Client> c, const std::string& why) {
  if (c->closed) return;
  c->closed = true;
  boost::system::error_code ec;
  c->socket.shutdown(tcp::socket::shutdown_both, ec);
  c->socket.close(ec);
  clients_.erase(c->id);
  spdlog::info("client {} ({}) closed: {}; {} readings dropped for it", c->id, c->peer, why,
               c->dropped);
}

void ClientHub::checkStalls() {
  const auto stall = std::chrono::duration<double>(limits_.stall_s);
  std::vector<std::shared_ptr<Client>> stuck;
  for (const auto& [id, c] : clients_)
    if (!c->queue.empty() && Clock::now() - c->last_progress > stall) stuck.push_back(c);
  for (const auto& c : stuck) {
    ++stalled_;
    close(c, "stuck: took nothing for " + std::to_string(limits_.stall_s) + " s");
  }
  const auto request_timeout = std::chrono::duration<double>(limits_.request_timeout_s);
  std::vector<std::shared_ptr<Client>> slow;
  for (const auto& [id, c] : clients_)
    if (c->line_started && Clock::now() - *c->line_started > request_timeout) slow.push_back(c);
  for (const auto& c : slow) {
    ++timed_out_;
    close(c, "a request line left unfinished for " + std::to_string(limits_.request_timeout_s) +
                 " s (request_timeout_s)");
  }
  stall_timer_.expires_after(std::chrono::milliseconds(250));
  stall_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) checkStalls();
  });
}

nlohmann::json ClientHub::stats() const {
  nlohmann::json per = nlohmann::json::array();
  for (const auto& [id, c] : clients_)
    per.push_back({{"id", id},
                   {"peer", c->peer},
                   {"watching", c->watching},
                   {"queued", c->queue.size()},
                   {"dropped", c->dropped}});
  return {{"connected", clients_.size()},
          {"refused", refused_},
          {"stalled", stalled_},
          {"timed_out", timed_out_},
          {"dropped_lines", dropped_lines_},
          {"clients", per}};
}

}  // namespace robocal::daemon
