#pragma once
// Serves a simulated SCPI instrument on a TCP port (what `piezobench
// sim-instrument` runs): one client at a time, each connection a fresh
// framer; a fault reply may close the connection.
#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "drivers/sim/scpi_device.hpp"

namespace piezo::drivers::sim {

class TcpServer {
 public:
  // Binds host:port (port 0 = any free port; see port()). Throws std::runtime_error.
  TcpServer(std::shared_ptr<ScpiDevice> dev, const std::string& host, std::uint16_t port);
  ~TcpServer();
  TcpServer(const TcpServer&) = delete;
  TcpServer& operator=(const TcpServer&) = delete;

  std::uint16_t port() const { return port_; }
  void start();  // serves on a background thread
  void stop();

 private:
  void serve();
  void serve_client(int fd);

  std::shared_ptr<ScpiDevice> dev_;
  int listen_fd_ = -1;
  std::uint16_t port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace piezo::drivers::sim
