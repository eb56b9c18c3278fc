// Browsers for robocal-bench-stream --browsers N: N WebSocket clients on robocald's web port,
// each watching the stream as the console page does and reading every message, on a thread of
// their own. They stand for the browsers' network side; a browser's drawing costs its own
// machine, not the cell PC.
#pragma once

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>

#include <algorithm>
#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace robocal::bench {

class BrowserLoad {
 public:
  BrowserLoad(unsigned short web_port, int browsers) {
    namespace websocket = boost::beast::websocket;
    for (int i = 0; i < browsers; ++i) {
      auto b = std::make_unique<Browser>(io_);
      b->ws.next_layer().connect({boost::asio::ip::make_address("127.0.0.1"), web_port});
      const std::string host = "127.0.0.1:" + std::to_string(web_port);
      b->ws.set_option(websocket::stream_base::decorator([host](websocket::request_type& req) {
        req.set(boost::beast::http::field::origin, "http://" + host);
      }));
      b->ws.handshake(host, "/ws");
      b->ws.write(boost::asio::buffer(std::string("{\"cmd\":\"watch\",\"enable\":true}")));
      browsers_.push_back(std::move(b));
    }
    for (auto& b : browsers_) read(*b);
    thread_ = std::thread([this] { io_.run(); });
  }
  ~BrowserLoad() {
    io_.stop();
    thread_.join();
  }
  BrowserLoad(const BrowserLoad&) = delete;
  BrowserLoad& operator=(const BrowserLoad&) = delete;

  // Messages received per browser so far: the fewest and the most.
  std::pair<long, long> received() const {
    long lo = -1, hi = 0;
    for (const auto& b : browsers_) {
      const long n = b->messages.load();
      lo = lo < 0 ? n : std::min(lo, n);
      hi = std::max(hi, n);
    }
    return {std::max(lo, 0L), hi};
  }
  int closed() const {
    return static_cast<int>(std::count_if(browsers_.begin(), browsers_.end(),
                                          [](const auto& b) { return b->gone.load(); }));
  }

 private:
  struct Browser {
    explicit Browser(boost::asio::io_context& io) : ws(io) {}
    boost::beast::websocket::stream<boost::asio::ip::tcp::socket> ws;
    boost::beast::flat_buffer buffer;
    std::atomic<long> messages{0};
    std::atomic<bool> gone{false};
  };
  void read(Browser& b) {
    b.ws.async_read(b.buffer, [this, &b](const boost::beast::error_code& ec, std::size_t) {
      if (ec) {
        b.gone = true;
        return;
      }
      ++b.messages;
      b.buffer.consume(b.buffer.size());
      read(b);
    });
  }
  boost::asio::io_context io_;
  std::vector<std::unique_ptr<Browser>> browsers_;
  std::thread thread_;
};

}  // namespace robocal::bench
