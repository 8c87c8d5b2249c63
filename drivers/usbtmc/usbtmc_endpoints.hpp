#pragma once
// The four USB operations USBTMC needs, so the protocol can run against
// libusb (LibusbEndpoints) or a scripted device in tests (FakeUsbTmcDevice).
// Implementations throw UsbIoError; the transport maps it to TransportError.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>

#include "drivers/usbtmc/usbtmc_protocol.hpp"

namespace piezo::drivers::usbtmc {

class UsbIoError : public std::runtime_error {
 public:
  enum class Code { Timeout, Stall, NoDevice, Io };
  UsbIoError(Code c, const std::string& msg) : std::runtime_error(msg), code_(c) {}
  Code code() const { return code_; }

 private:
  Code code_;
};

class UsbTmcEndpoints {
 public:
  virtual ~UsbTmcEndpoints() = default;

  virtual std::uint8_t interface_number() const = 0;
  virtual std::uint8_t bulk_out_address() const = 0;  // e.g. 0x02
  virtual std::uint8_t bulk_in_address() const = 0;   // e.g. 0x81
  virtual std::size_t max_packet_size() const = 0;    // bulk-IN wMaxPacketSize

  // Writes all bytes as one bulk transfer.
  virtual void bulk_out(std::span<const std::uint8_t> bytes, std::chrono::milliseconds timeout) = 0;
  // One bulk read: returns when `max` bytes arrived or a short packet ended
  // the transfer (0 for a zero-length packet). `max` is a multiple of the
  // packet size, or the device may overflow the buffer.
  virtual std::size_t bulk_in(std::uint8_t* buf, std::size_t max,
                              std::chrono::milliseconds timeout) = 0;
  // A device-to-host control transfer; returns the reply length.
  virtual std::size_t control_in(const ControlSetup& setup, std::uint8_t* buf,
                                 std::chrono::milliseconds timeout) = 0;
  // CLEAR_FEATURE(ENDPOINT_HALT) on an endpoint address.
  virtual void clear_halt(std::uint8_t endpoint) = 0;
};

}  // namespace piezo::drivers::usbtmc
