#pragma once
// LibusbEndpoints: the thin libusb-1.0 shim under UsbTmcTransport. It finds
// the device (VID:PID, optionally by iSerialNumber), its USBTMC interface
// (class 0xFE, subclass 0x03) and bulk endpoints, detaches a kernel driver
// (usbtmc.ko) if bound, claims the interface, and does the four transfers.
// No protocol logic here; libusb.h stays out of this header.
#include <memory>
#include <optional>
#include <string>

#include "drivers/usbtmc/usbtmc_endpoints.hpp"

namespace piezo::drivers::usbtmc {

class LibusbEndpoints final : public UsbTmcEndpoints {
 public:
  // Throws TransportError(Io / Closed) with a message for the user, prefixed
  // with `address`: "no USB device 0957:2807", "permission denied: add a udev
  // rule ...", "serial X not found; found: A, B", "no USBTMC interface".
  static std::unique_ptr<LibusbEndpoints> open(std::uint16_t vid, std::uint16_t pid,
                                               const std::optional<std::string>& serial,
                                               const std::string& address);
  ~LibusbEndpoints() override;
  LibusbEndpoints(const LibusbEndpoints&) = delete;
  LibusbEndpoints& operator=(const LibusbEndpoints&) = delete;

  std::uint8_t interface_number() const override;
  std::uint8_t bulk_out_address() const override;
  std::uint8_t bulk_in_address() const override;
  std::size_t max_packet_size() const override;

  void bulk_out(std::span<const std::uint8_t> bytes, std::chrono::milliseconds timeout) override;
  std::size_t bulk_in(std::uint8_t* buf, std::size_t max,
                      std::chrono::milliseconds timeout) override;
  std::size_t control_in(const ControlSetup& setup, std::uint8_t* buf,
                         std::chrono::milliseconds timeout) override;
  void clear_halt(std::uint8_t endpoint) override;

  struct Impl;

 private:
  explicit LibusbEndpoints(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace piezo::drivers::usbtmc
