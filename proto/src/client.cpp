#include <robocal/proto/client.hpp>

#include <boost/asio/connect.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/read_until.hpp>
#include <boost/asio/streambuf.hpp>
#include <boost/asio/write.hpp>

#include <chrono>
#include <istream>
#include <set>

namespace robocal::proto {

namespace asio = boost::asio;
using tcp = asio::ip::tcp;

struct Client::Impl {
  asio::io_context io;
  tcp::socket socket{io};
  asio::streambuf buffer;

  // Runs one async operation to completion or the timeout (then cancels it).
  template <typename Start>
  bool runFor(double timeout_s, Start start) {
    bool done = false;
    start(done);
    io.restart();
    io.run_for(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(timeout_s)));
    if (done) return true;
    socket.cancel();
    io.restart();
    io.run();  // let the cancelled handler finish; the operation still counts as timed out
    return false;
  }
};

Client::Client(const std::string& host, unsigned short port, double timeout_s)
    : impl_(std::make_unique<Impl>()) {
  tcp::resolver resolver(impl_->io);
  boost::system::error_code ec;
  const auto endpoints = resolver.resolve(host, std::to_string(port), ec);
  if (ec) throw ClientError("cannot resolve " + host + ": " + ec.message());
  boost::system::error_code connect_ec = asio::error::timed_out;
  impl_->runFor(timeout_s, [&](bool& done) {
    asio::async_connect(impl_->socket, endpoints,
                        [&](const boost::system::error_code& e, const tcp::endpoint&) {
                          connect_ec = e;
                          done = true;
                        });
  });
  if (connect_ec)
    throw ClientError("cannot connect to robocald at " + host + ":" + std::to_string(port) + ": " +
                      connect_ec.message());
  const auto banner = read(timeout_s);
  if (!banner || banner->value("class", "") != "VERSION")
    throw ClientError("no VERSION banner from " + host + ":" + std::to_string(port));
  version_ = *banner;
}

Client::~Client() = default;

void Client::send(const nlohmann::json& request) {
  sendRaw(request.dump() + "\n");
}

void Client::sendRaw(const std::string& bytes) {
  boost::system::error_code ec;
  asio::write(impl_->socket, asio::buffer(bytes), ec);
  if (ec) throw ClientError("cannot send to robocald: " + ec.message());
}

std::optional<nlohmann::json> Client::read(double timeout_s) {
  boost::system::error_code ec;
  std::size_t n = 0;
  const bool done = impl_->runFor(timeout_s, [&](bool& finished) {
    asio::async_read_until(impl_->socket, impl_->buffer, '\n',
                           [&](const boost::system::error_code& e, std::size_t bytes) {
                             ec = e;
                             n = bytes;
                             finished = true;
                           });
  });
  if (!done) return std::nullopt;
  if (ec) throw ClientError("robocald closed the connection: " + ec.message());
  std::string line(asio::buffers_begin(impl_->buffer.data()),
                   asio::buffers_begin(impl_->buffer.data()) + static_cast<std::ptrdiff_t>(n));
  impl_->buffer.consume(n);
  try {
    return nlohmann::json::parse(line);
  } catch (const nlohmann::json::exception& e) {
    throw ClientError(std::string("robocald sent a line that is not JSON: ") + e.what());
  }
}

nlohmann::json Client::request(const nlohmann::json& req, double timeout_s,
                               const std::string& want) {
  send(req);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (true) {
    const double left =
        std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0)
      throw ClientError("no reply from robocald within " + std::to_string(timeout_s) + " s");
    auto reply = read(left);
    if (!reply) continue;
    const std::string cls = reply->value("class", "");
    if (want.empty() || cls == want || cls == "ERROR") return *reply;
  }
}

}  // namespace robocal::proto
