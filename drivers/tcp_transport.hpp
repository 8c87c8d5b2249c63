#pragma once
// Raw SCPI socket (LXI instruments listen on TCP port 5025).
#include <string>

#include "drivers/transport.hpp"

namespace piezo::drivers {

class TcpTransport : public Transport {
 public:
  // Connects (with the timeout); throws TransportError naming host:port and the reason.
  TcpTransport(const std::string& host, std::uint16_t port,
               std::chrono::milliseconds timeout = std::chrono::milliseconds(5000));
  ~TcpTransport() override;
  TcpTransport(const TcpTransport&) = delete;
  TcpTransport& operator=(const TcpTransport&) = delete;

  std::string address() const override;
  void send(std::span<const std::uint8_t> bytes) override;
  std::size_t receive(std::uint8_t* buf, std::size_t max, bool* end_of_message) override;
  void set_timeout(std::chrono::milliseconds t) override { timeout_ = t; }
  std::chrono::milliseconds timeout() const override { return timeout_; }
  void clear() override;
  using Transport::send;

 private:
  std::string host_;
  std::uint16_t port_;
  int fd_ = -1;
  std::chrono::milliseconds timeout_;
};

}  // namespace piezo::drivers
