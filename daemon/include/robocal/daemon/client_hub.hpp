// The TCP side of robocald: accepts clients, splits their bytes into request lines (bounded),
// and sends each client its own bounded queue of JSON lines. A slow watcher loses BAR readings
// (counted), a stuck one is disconnected; neither ever blocks the event loop or other clients.
#pragma once

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>

#include <robocal/proto/objects.hpp>

#include <nlohmann/json.hpp>

#include <chrono>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <string>

namespace robocal::daemon {

// Every client socket robocald accepts, TCP protocol and web port alike: lines go out as they
// come (TCP_NODELAY), and the kernel holds at most `unsent_max_bytes` not yet sent
// (TCP_NOTSENT_LOWAT), so that a client that stops reading shows as writes that make no progress
// within seconds (the stall limit), not after megabytes of auto-tuned socket buffers.
void configureClientSocket(boost::asio::ip::tcp::socket& socket, int unsent_max_bytes);

struct HubLimits {
  int max_clients = 64;
  std::size_t max_line_bytes = 16 * 1024;
  std::size_t queue_max = 4096;  // queued lines per client; past it droppable lines are dropped
  double stall_s = 5.0;          // queued data and no write progress this long: disconnect
  // TCP_NOTSENT_LOWAT of each client socket: the kernel takes at most this much more than what
  // is in flight, so a client whose window has closed is seen as stalled (its queue stops moving)
  // after ~this many bytes rather than after the kernel's auto-tuned send buffer (MBs) fills.
  int unsent_max_bytes = 16 * 1024;
  // A request line begun and not ended this long (a client sending a byte now and then, or a
  // line cut off): the client is disconnected.
  double request_timeout_s = 10.0;
};

// Opens, binds (reusing the address) and listens on `acceptor`: the TCP and web ports alike.
// Throws boost::system::system_error (a port in use, an address not on this host).
void bindAndListen(boost::asio::ip::tcp::acceptor& acceptor, const std::string& address,
                   unsigned short port);

class ClientHub {
 public:
  using ClientId = std::uint64_t;
  // Called on the event loop for each complete request line of a client.
  using LineHandler = std::function<void(ClientId, const std::string& line)>;

  ClientHub(boost::asio::io_context& io, HubLimits limits, LineHandler on_line,
            std::function<nlohmann::json()> greeting);
  ~ClientHub();

  // Binds and listens; returns the bound port (useful with port 0). Throws on failure.
  unsigned short listen(const std::string& address, unsigned short port);

  void send(ClientId client, const nlohmann::json& object);
  // To every client that asked to watch. Droppable objects (BAR) are skipped for full queues.
  void broadcast(const nlohmann::json& object, bool droppable);
  void setWatching(ClientId client, bool watching);
  std::size_t clientCount() const { return clients_.size(); }
  nlohmann::json stats() const;  // per client, and the counts below
  proto::ClientCounts counts() const { return {refused_, stalled_, timed_out_, dropped_lines_}; }

 private:
  struct Client;
  void accept();
  void read(const std::shared_ptr<Client>& c);
  void enqueue(const std::shared_ptr<Client>& c, std::string line, bool droppable);
  void write(const std::shared_ptr<Client>& c);
  // By value: the map's own pointer may be what is erased.
  void close(std::shared_ptr<Client> c, const std::string& why);
  void checkStalls();

  boost::asio::io_context& io_;
  HubLimits limits_;
  LineHandler on_line_;
  std::function<nlohmann::json()> greeting_;
  boost::asio::ip::tcp::acceptor acceptor_;
  boost::asio::steady_timer stall_timer_;
  std::map<ClientId, std::shared_ptr<Client>> clients_;
  ClientId next_id_ = 1;
  long refused_ = 0, stalled_ = 0, dropped_lines_ = 0, timed_out_ = 0;
};

}  // namespace robocal::daemon
