#pragma once
// In-process Transport to a simulated instrument: the bytes go through the
// same SCPI framing and the same device code as over TCP, without a socket.
#include <deque>
#include <memory>

#include "drivers/scpi_parse.hpp"
#include "drivers/sim/scpi_device.hpp"
#include "drivers/transport.hpp"

namespace piezo::drivers::sim {

class LoopbackTransport : public Transport {
 public:
  LoopbackTransport(std::shared_ptr<ScpiDevice> dev, std::string name)
      : dev_(std::move(dev)), name_(std::move(name)) {}
  std::string address() const override { return name_; }
  void send(std::span<const std::uint8_t> bytes) override;
  std::size_t receive(std::uint8_t* buf, std::size_t max, bool* end_of_message) override;
  void set_timeout(std::chrono::milliseconds t) override { timeout_ = t; }
  std::chrono::milliseconds timeout() const override { return timeout_; }
  void clear() override { out_.clear(); }
  using Transport::send;

 private:
  std::shared_ptr<ScpiDevice> dev_;
  std::string name_;
  scpi::InputFramer framer_;
  std::deque<std::uint8_t> out_;
  bool closed_ = false;
  bool close_pending_ = false;
  std::chrono::milliseconds timeout_{5000};
};

}  // namespace piezo::drivers::sim
