#pragma once
// USBTMC 1.0 / USB488 framing, as pure functions: bulk-OUT and bulk-IN
// headers, bTag sequencing, message splitting, bulk-IN read sizing and the
// class requests (setup packets and their status replies). No I/O here: the
// transport drives these over a UsbTmcEndpoints (libusb or the test fake).
//
// References: USBTMC 1.0 (USB-IF, 2003) sections 3.2 (bulk-OUT), 3.3
// (bulk-IN) and 4.2.1 (class requests); USB488 1.0 for the subclass.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace piezo::drivers::usbtmc {

inline constexpr std::size_t kHeaderSize = 12;
inline constexpr std::uint8_t kInterfaceClass = 0xFE;     // application specific
inline constexpr std::uint8_t kInterfaceSubClass = 0x03;  // USBTMC

enum class MsgId : std::uint8_t {
  DevDepMsgOut = 1,        // host -> device, carries a message
  RequestDevDepMsgIn = 2,  // host -> device, asks for a response transfer
  DevDepMsgIn = 2,         // device -> host, the response transfer
};

// bmTransferAttributes bits.
inline constexpr std::uint8_t kAttrEom = 0x01;              // DEV_DEP_MSG_OUT / _IN
inline constexpr std::uint8_t kAttrTermCharEnabled = 0x02;  // REQUEST_DEV_DEP_MSG_IN
inline constexpr std::uint8_t kAttrTermCharMatched = 0x02;  // DEV_DEP_MSG_IN

// bTag: 1..255, incremented per bulk-OUT transfer, never 0 (spec 3.2 Table 1).
class TagCounter {
 public:
  std::uint8_t next() {
    last_ = static_cast<std::uint8_t>(last_ == 255 ? 1 : last_ + 1);
    return last_;
  }
  std::uint8_t last() const { return last_; }  // 0 before the first next()

 private:
  std::uint8_t last_ = 0;
};

using Header = std::array<std::uint8_t, kHeaderSize>;

Header encode_dev_dep_msg_out(std::uint8_t tag, std::uint32_t transfer_size, bool eom);
Header encode_request_dev_dep_msg_in(std::uint8_t tag, std::uint32_t max_size,
                                     std::optional<std::uint8_t> term_char);

// A message cut into DEV_DEP_MSG_OUT transfers: each is header + chunk,
// zero-padded to a multiple of 4; only the last carries EOM. An empty
// message is one transfer with TransferSize 0 and EOM.
// `max_transfer` bounds a whole transfer (header + payload + padding); it
// must be a multiple of 4 and at least kHeaderSize + 4.
std::vector<std::vector<std::uint8_t>> frame_message(std::span<const std::uint8_t> message,
                                                     TagCounter& tags, std::size_t max_transfer);

struct BulkInHeader {
  std::uint8_t tag = 0;
  std::uint32_t transfer_size = 0;  // payload bytes in this transfer (no header, no padding)
  bool eom = false;
  bool term_char_matched = false;
};

// Validates a DEV_DEP_MSG_IN header against the request it answers; throws
// TransportError(Protocol) naming the offending field. `requested` is the
// TransferSize of the REQUEST_DEV_DEP_MSG_IN (the device may not exceed it).
BulkInHeader parse_dev_dep_msg_in(std::span<const std::uint8_t> header, std::uint8_t expected_tag,
                                  std::uint32_t requested);

constexpr std::size_t round_up(std::size_t n, std::size_t m) { return (n + m - 1) / m * m; }

// A transfer on the wire: header + payload + padding to 4.
constexpr std::size_t wire_size(std::size_t payload) { return round_up(kHeaderSize + payload, 4); }

// Bytes to ask of one bulk-IN read when `left` wire bytes of the transfer are
// still expected. A device ends every bulk-IN transfer with a short packet
// (a zero-length one when the data fill whole packets), so ask for one byte
// more than expected, rounded up to packets: the terminating short packet
// then lands inside this read. Capped at `cap` (a multiple of the packet size).
std::size_t bulk_in_read_size(std::size_t left, std::size_t max_packet, std::size_t cap);

// How a device cuts a transfer into packets (used by the fake device and to
// check read sizes): full packets, then a short one; a zero-length packet
// when the transfer is a multiple of max_packet.
std::vector<std::size_t> packet_sizes(std::size_t transfer_bytes, std::size_t max_packet);

// ---- Class requests (spec 4.2.1) ----

enum class Request : std::uint8_t {
  InitiateAbortBulkOut = 1,
  CheckAbortBulkOutStatus = 2,
  InitiateAbortBulkIn = 3,
  CheckAbortBulkInStatus = 4,
  InitiateClear = 5,
  CheckClearStatus = 6,
  GetCapabilities = 7,
};

enum class Status : std::uint8_t {
  Success = 0x01,
  Pending = 0x02,
  Failed = 0x80,
  TransferNotInProgress = 0x81,
  SplitNotInProgress = 0x82,
  SplitInProgress = 0x83,
};

std::string to_string(Status s);
std::string to_string(Request r);

// A device-to-host control setup packet.
struct ControlSetup {
  std::uint8_t request_type = 0;  // bmRequestType
  std::uint8_t request = 0;       // bRequest
  std::uint16_t value = 0;        // wValue
  std::uint16_t index = 0;        // wIndex
  std::uint16_t length = 0;       // wLength (reply bytes expected)
};

// bmRequestType: direction IN | type class | recipient interface / endpoint.
inline constexpr std::uint8_t kToHostClassInterface = 0xA1;
inline constexpr std::uint8_t kToHostClassEndpoint = 0xA2;

ControlSetup initiate_abort_bulk_out(std::uint8_t tag, std::uint8_t bulk_out_ep);
ControlSetup check_abort_bulk_out_status(std::uint8_t bulk_out_ep);
ControlSetup initiate_abort_bulk_in(std::uint8_t tag, std::uint8_t bulk_in_ep);
ControlSetup check_abort_bulk_in_status(std::uint8_t bulk_in_ep);
ControlSetup initiate_clear(std::uint8_t interface);
ControlSetup check_clear_status(std::uint8_t interface);

// Replies. Each throws TransportError(Protocol) when the reply is shorter
// than the spec's wLength for that request.
struct ClassReply {
  Status status = Status::Failed;
  bool in_fifo_has_data =
      false;                 // CHECK_CLEAR_STATUS bmClear.D0 / CHECK_ABORT_BULK_IN bmAbortBulkIn.D0
  std::uint32_t nbytes = 0;  // CHECK_ABORT_*_STATUS NBYTES_RXD / NBYTES_TXD
};
ClassReply parse_class_reply(Request r, std::span<const std::uint8_t> reply);

}  // namespace piezo::drivers::usbtmc
