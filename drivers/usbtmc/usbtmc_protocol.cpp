#include "drivers/usbtmc/usbtmc_protocol.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "drivers/transport.hpp"

namespace piezo::drivers::usbtmc {

namespace {
void put_le32(std::uint8_t* p, std::uint32_t v) {
  p[0] = static_cast<std::uint8_t>(v);
  p[1] = static_cast<std::uint8_t>(v >> 8);
  p[2] = static_cast<std::uint8_t>(v >> 16);
  p[3] = static_cast<std::uint8_t>(v >> 24);
}

std::uint32_t get_le32(const std::uint8_t* p) {
  return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 |
         std::uint32_t{p[3]} << 24;
}

Header bulk_out_header(MsgId id, std::uint8_t tag) {
  if (tag == 0) throw std::invalid_argument("usbtmc bulk-OUT header: bTag 0 is reserved");
  Header h{};
  h[0] = static_cast<std::uint8_t>(id);
  h[1] = tag;
  h[2] = static_cast<std::uint8_t>(~tag);
  return h;
}

[[noreturn]] void protocol(const std::string& what) {
  throw TransportError(TransportError::Kind::Protocol, "USBTMC protocol error: " + what);
}
}  // namespace

Header encode_dev_dep_msg_out(std::uint8_t tag, std::uint32_t transfer_size, bool eom) {
  Header h = bulk_out_header(MsgId::DevDepMsgOut, tag);
  put_le32(&h[4], transfer_size);
  h[8] = eom ? kAttrEom : 0;
  return h;
}

Header encode_request_dev_dep_msg_in(std::uint8_t tag, std::uint32_t max_size,
                                     std::optional<std::uint8_t> term_char) {
  Header h = bulk_out_header(MsgId::RequestDevDepMsgIn, tag);
  put_le32(&h[4], max_size);
  h[8] = term_char ? kAttrTermCharEnabled : 0;
  h[9] = term_char.value_or(0);
  return h;
}

std::vector<std::vector<std::uint8_t>> frame_message(std::span<const std::uint8_t> message,
                                                     TagCounter& tags, std::size_t max_transfer) {
  if (max_transfer % 4 != 0 || max_transfer < kHeaderSize + 4)
    throw std::invalid_argument("usbtmc frame_message: max_transfer " +
                                std::to_string(max_transfer) +
                                " must be a multiple of 4 and at least 16");
  const std::size_t max_payload = max_transfer - kHeaderSize;
  std::vector<std::vector<std::uint8_t>> out;
  std::size_t pos = 0;
  do {
    const std::size_t n = std::min(max_payload, message.size() - pos);
    const bool last = pos + n == message.size();
    const Header h = encode_dev_dep_msg_out(tags.next(), static_cast<std::uint32_t>(n), last);
    std::vector<std::uint8_t> t(wire_size(n), 0);  // zero padding to 4 (spec 3.2.1.1)
    std::copy(h.begin(), h.end(), t.begin());
    std::copy_n(message.begin() + static_cast<std::ptrdiff_t>(pos), n, t.begin() + kHeaderSize);
    out.push_back(std::move(t));
    pos += n;
  } while (pos < message.size());
  return out;
}

BulkInHeader parse_dev_dep_msg_in(std::span<const std::uint8_t> h, std::uint8_t expected_tag,
                                  std::uint32_t requested) {
  if (h.size() < kHeaderSize)
    protocol("bulk-IN header is " + std::to_string(h.size()) + " bytes, expected 12");
  if (h[0] != static_cast<std::uint8_t>(MsgId::DevDepMsgIn))
    protocol("bulk-IN MsgID " + std::to_string(h[0]) + ", expected DEV_DEP_MSG_IN (2)");
  if (h[1] != expected_tag)
    protocol("bulk-IN bTag " + std::to_string(h[1]) + " does not answer request bTag " +
             std::to_string(expected_tag));
  if (h[2] != static_cast<std::uint8_t>(~h[1]))
    protocol("bulk-IN bTagInverse " + std::to_string(h[2]) + " does not match bTag " +
             std::to_string(h[1]));
  BulkInHeader r;
  r.tag = h[1];
  r.transfer_size = get_le32(&h[4]);
  r.eom = (h[8] & kAttrEom) != 0;
  r.term_char_matched = (h[8] & kAttrTermCharMatched) != 0;
  if (r.transfer_size > requested)
    protocol("device sends " + std::to_string(r.transfer_size) + " bytes, more than the " +
             std::to_string(requested) + " requested");
  return r;
}

std::size_t bulk_in_read_size(std::size_t left, std::size_t max_packet, std::size_t cap) {
  if (max_packet == 0 || cap < max_packet || cap % max_packet != 0)
    throw std::invalid_argument("usbtmc bulk_in_read_size: cap must be a multiple of max_packet");
  return std::min(round_up(left + 1, max_packet), cap);
}

std::vector<std::size_t> packet_sizes(std::size_t transfer_bytes, std::size_t max_packet) {
  std::vector<std::size_t> p(transfer_bytes / max_packet, max_packet);
  p.push_back(transfer_bytes % max_packet);  // the short (possibly zero-length) packet
  return p;
}

std::string to_string(Status s) {
  switch (s) {
    case Status::Success:
      return "STATUS_SUCCESS";
    case Status::Pending:
      return "STATUS_PENDING";
    case Status::Failed:
      return "STATUS_FAILED";
    case Status::TransferNotInProgress:
      return "STATUS_TRANSFER_NOT_IN_PROGRESS";
    case Status::SplitNotInProgress:
      return "STATUS_SPLIT_NOT_IN_PROGRESS";
    case Status::SplitInProgress:
      return "STATUS_SPLIT_IN_PROGRESS";
  }
  char buf[24];
  std::snprintf(buf, sizeof buf, "status 0x%02x", static_cast<unsigned>(s));
  return buf;
}

std::string to_string(Request r) {
  switch (r) {
    case Request::InitiateAbortBulkOut:
      return "INITIATE_ABORT_BULK_OUT";
    case Request::CheckAbortBulkOutStatus:
      return "CHECK_ABORT_BULK_OUT_STATUS";
    case Request::InitiateAbortBulkIn:
      return "INITIATE_ABORT_BULK_IN";
    case Request::CheckAbortBulkInStatus:
      return "CHECK_ABORT_BULK_IN_STATUS";
    case Request::InitiateClear:
      return "INITIATE_CLEAR";
    case Request::CheckClearStatus:
      return "CHECK_CLEAR_STATUS";
    case Request::GetCapabilities:
      return "GET_CAPABILITIES";
  }
  return "request " + std::to_string(static_cast<unsigned>(r));
}

namespace {
// wLength of each reply, spec 4.2.1.2 - 4.2.1.7.
std::uint16_t reply_length(Request r) {
  switch (r) {
    case Request::InitiateAbortBulkOut:
    case Request::InitiateAbortBulkIn:
    case Request::CheckClearStatus:
      return 2;
    case Request::CheckAbortBulkOutStatus:
    case Request::CheckAbortBulkInStatus:
      return 8;
    case Request::InitiateClear:
      return 1;
    case Request::GetCapabilities:
      return 0x18;
  }
  return 0;
}

ControlSetup setup(Request r, std::uint8_t type, std::uint16_t value, std::uint16_t index) {
  return ControlSetup{type, static_cast<std::uint8_t>(r), value, index, reply_length(r)};
}
}  // namespace

ControlSetup initiate_abort_bulk_out(std::uint8_t tag, std::uint8_t ep) {
  return setup(Request::InitiateAbortBulkOut, kToHostClassEndpoint, tag, ep);
}
ControlSetup check_abort_bulk_out_status(std::uint8_t ep) {
  return setup(Request::CheckAbortBulkOutStatus, kToHostClassEndpoint, 0, ep);
}
ControlSetup initiate_abort_bulk_in(std::uint8_t tag, std::uint8_t ep) {
  return setup(Request::InitiateAbortBulkIn, kToHostClassEndpoint, tag, ep);
}
ControlSetup check_abort_bulk_in_status(std::uint8_t ep) {
  return setup(Request::CheckAbortBulkInStatus, kToHostClassEndpoint, 0, ep);
}
ControlSetup initiate_clear(std::uint8_t interface) {
  return setup(Request::InitiateClear, kToHostClassInterface, 0, interface);
}
ControlSetup check_clear_status(std::uint8_t interface) {
  return setup(Request::CheckClearStatus, kToHostClassInterface, 0, interface);
}

ClassReply parse_class_reply(Request r, std::span<const std::uint8_t> b) {
  const std::size_t need = reply_length(r);
  if (b.size() < need)
    protocol(to_string(r) + " reply is " + std::to_string(b.size()) + " bytes, expected " +
             std::to_string(need));
  ClassReply c;
  c.status = static_cast<Status>(b[0]);
  switch (r) {
    case Request::CheckClearStatus:
    case Request::CheckAbortBulkInStatus:
      c.in_fifo_has_data = (b[1] & 0x01) != 0;
      break;
    default:
      break;
  }
  if (need == 8) c.nbytes = get_le32(&b[4]);
  return c;
}

}  // namespace piezo::drivers::usbtmc
