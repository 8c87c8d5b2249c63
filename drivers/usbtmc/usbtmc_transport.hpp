#pragma once
// UsbTmcTransport: the Transport for USBTMC (USB488) instruments. send() is
// one DEV_DEP_MSG_OUT message (split into transfers, EOM on the last);
// receive() issues REQUEST_DEV_DEP_MSG_IN and streams the DEV_DEP_MSG_IN
// payload, reporting EOM. A timeout runs the abort sequence before throwing
// TransportError::Timeout; clear() is the INITIATE_CLEAR sequence.
//
//   auto t = open_usbtmc(parse_instrument_uri("usbtmc://0957:2807/MY1234"));
//
// Tests construct it directly over a FakeUsbTmcDevice.
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/instrument_uri.hpp"
#include "drivers/transport.hpp"
#include "drivers/usbtmc/usbtmc_endpoints.hpp"
#include "drivers/usbtmc/usbtmc_protocol.hpp"
#include "drivers/usbtmc/usbtmc_sequences.hpp"

namespace piezo::drivers {

struct UsbTmcOptions {
  std::chrono::milliseconds timeout{5000};
  // Largest DEV_DEP_MSG_OUT transfer, header and padding included (multiple
  // of 4). 2048 matches the buffers of Linux usbtmc and libsigrok.
  std::size_t max_out_transfer = 2048;
  // TransferSize asked by each REQUEST_DEV_DEP_MSG_IN; longer responses come
  // as several transfers, the last with EOM.
  std::uint32_t in_request_size = 1u << 20;
  // Upper bound of one bulk-IN read (rounded down to whole packets).
  std::size_t max_in_read = 64 * 1024;
  // When set, REQUEST_DEV_DEP_MSG_IN enables TermChar (the device must
  // report the TermChar capability); transfers may then end at this byte.
  std::optional<std::uint8_t> term_char;
  usbtmc::SequencePolicy sequences;
};

// The largest TransferSize a request may ask (the field is 32-bit; stay in
// int32 range as libsigrok does, some firmware treats it as signed).
inline constexpr std::uint32_t kWholeMessageRequest = 0x7FFFFFFF;

// Applies the quirk table entry for vid:pid (if any) to `opts`.
UsbTmcOptions with_quirks(UsbTmcOptions opts, std::uint16_t vid, std::uint16_t pid);

class UsbTmcTransport final : public Transport {
 public:
  UsbTmcTransport(std::unique_ptr<usbtmc::UsbTmcEndpoints> endpoints, std::string address,
                  UsbTmcOptions opts = {});

  std::string address() const override { return address_; }
  void send(std::span<const std::uint8_t> bytes) override;
  using Transport::send;
  std::size_t receive(std::uint8_t* buf, std::size_t max, bool* end_of_message) override;
  void set_timeout(std::chrono::milliseconds t) override { opts_.timeout = t; }
  std::chrono::milliseconds timeout() const override { return opts_.timeout; }
  void clear() override;

  const UsbTmcOptions& options() const { return opts_; }

 private:
  void start_transfer();
  void read_more();
  void reset_input();
  [[noreturn]] void fail(const usbtmc::UsbIoError& e, std::uint8_t endpoint, const char* during);
  [[noreturn]] void fail(TransportError::Kind k, const std::string& what);

  std::unique_ptr<usbtmc::UsbTmcEndpoints> ep_;
  std::string address_;
  UsbTmcOptions opts_;
  usbtmc::TagCounter tags_;

  // Input state: one DEV_DEP_MSG_IN transfer at a time.
  std::vector<std::uint8_t> rx_;             // last bulk-IN read
  std::size_t win_begin_ = 0, win_end_ = 0;  // its payload bytes not yet returned
  bool open_ = false;                        // transfer not yet ended by a short packet
  std::uint8_t request_tag_ = 0;
  std::uint32_t requested_ = 0;
  usbtmc::Header header_{};
  std::size_t header_bytes_ = 0;  // of header_ received so far
  usbtmc::BulkInHeader in_{};
  std::size_t wire_got_ = 0;  // bytes of this transfer read, header included
  std::size_t payload_got_ = 0;
  bool zero_length_eom_ = false;  // a TransferSize 0 transfer with EOM, to report
};

// Opens usbtmc://VID:PID[/SERIAL] through libusb and applies the quirk
// table. Throws TransportError (Io/Closed) with a message naming the address
// and the fix ("no USB device 0957:2807", "permission denied: add a udev rule ...").
std::unique_ptr<UsbTmcTransport> open_usbtmc(const InstrumentUri& uri, UsbTmcOptions opts = {});

}  // namespace piezo::drivers
