#pragma once
// A Transport is a byte pipe to one instrument, with timeouts (after
// libscopehal's SCPITransport). Implementations: TcpTransport (raw SCPI
// socket, LXI port 5025), UsbTmcTransport (USB488 over libusb), and
// LoopbackTransport (an in-process simulated instrument).
//
// Message semantics: send() writes one complete program message (the
// terminator is added by the SCPI layer); the reads return bytes as they
// arrive. All errors are TransportError with the address in the message.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace piezo::drivers {

class TransportError : public std::runtime_error {
 public:
  enum class Kind { Closed, Timeout, Io, Protocol };
  TransportError(Kind k, const std::string& msg) : std::runtime_error(msg), kind_(k) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

class Transport {
 public:
  virtual ~Transport() = default;

  // Address as the user wrote it ("tcp://10.0.0.5:5025"), for messages.
  virtual std::string address() const = 0;

  // Writes all bytes of one message (USBTMC: one DEV_DEP_MSG_OUT transfer with EOM).
  virtual void send(std::span<const std::uint8_t> bytes) = 0;

  // Reads at least one byte and at most `max` bytes, waiting up to the timeout.
  // Sets *end_of_message when the transport knows the message ended (USBTMC
  // EOM); byte-stream transports leave it false. Throws on timeout/close.
  virtual std::size_t receive(std::uint8_t* buf, std::size_t max, bool* end_of_message) = 0;

  virtual void set_timeout(std::chrono::milliseconds t) = 0;
  virtual std::chrono::milliseconds timeout() const = 0;

  // Device clear (USBTMC INITIATE_CLEAR; TCP: drop buffered input). Best effort.
  virtual void clear() {}

  void send(const std::string& s) {
    send(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()));
  }
};

}  // namespace piezo::drivers
