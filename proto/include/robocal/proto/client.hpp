// A small blocking client of robocald's protocol (for the robocal command line and the tests):
// one TCP connection, JSON lines in and out, every wait bounded by a timeout.
#pragma once

#include <nlohmann/json.hpp>

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

namespace robocal::proto {

class ClientError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Client {
 public:
  // Connects and reads the VERSION banner. ClientError when nobody answers.
  Client(const std::string& host, unsigned short port, double timeout_s = 5.0);
  ~Client();
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  const nlohmann::json& version() const { return version_; }
  void send(const nlohmann::json& request);
  void sendRaw(const std::string& bytes);  // for tests of malformed input
  // The next object from the server; nullopt on timeout. ClientError when the server closes.
  std::optional<nlohmann::json> read(double timeout_s);
  // Sends a request and returns the reply: the next object, or with `want` the next object of
  // that class or an ERROR (a watching client also receives the stream's objects).
  nlohmann::json request(const nlohmann::json& request, double timeout_s = 10.0,
                         const std::string& want = {});

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  nlohmann::json version_;
};

}  // namespace robocal::proto
