#include "tests/drivers/fake_usbtmc_device.hpp"

#include <algorithm>
#include <cstring>

namespace piezo::testing {

using ut::UsbIoError;

namespace {
std::uint32_t le32(const std::uint8_t* p) {
  return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 |
         std::uint32_t{p[3]} << 24;
}
}  // namespace

void FakeUsbTmcDevice::queue_transfer(State& s, std::uint8_t tag, const std::string& payload,
                                      bool eom) {
  std::vector<std::uint8_t> t(ut::wire_size(payload.size()), 0);
  t[0] = 2;  // DEV_DEP_MSG_IN
  t[1] = tag;
  t[2] = static_cast<std::uint8_t>(~tag);
  const auto n = static_cast<std::uint32_t>(payload.size());
  for (int i = 0; i < 4; ++i) t[4 + i] = static_cast<std::uint8_t>(n >> (8 * i));
  t[8] = eom ? ut::kAttrEom : 0;
  std::memcpy(t.data() + ut::kHeaderSize, payload.data(), payload.size());
  std::size_t pos = 0;
  for (std::size_t len : ut::packet_sizes(t.size(), s.cfg.max_packet)) {
    s.fifo.emplace_back(t.begin() + static_cast<std::ptrdiff_t>(pos),
                        t.begin() + static_cast<std::ptrdiff_t>(pos + len));
    pos += len;
  }
}

void FakeUsbTmcDevice::bulk_out(std::span<const std::uint8_t> b, std::chrono::milliseconds) {
  s_.out_transfers.emplace_back(b.begin(), b.end());
  if (s_.stall_bulk_out) throw UsbIoError(UsbIoError::Code::Stall, "fake: bulk-OUT stalled");
  if (s_.bulk_out_times_out) throw UsbIoError(UsbIoError::Code::Timeout, "fake: bulk-OUT timeout");
  auto violation = [&](const std::string& v) { s_.violations.push_back(v); };
  if (b.size() < ut::kHeaderSize) return violation("bulk-OUT shorter than a header");
  if (b.size() % 4 != 0) violation("bulk-OUT transfer not padded to 4");
  const std::uint8_t tag = b[1];
  if (tag == 0) violation("bTag 0");
  if (b[2] != static_cast<std::uint8_t>(~tag)) violation("bTagInverse wrong");
  if (b[3] != 0) violation("reserved byte 3 not 0");
  const std::uint8_t expected = s_.last_out_tag == 255 ? 1 : s_.last_out_tag + 1;
  if (s_.last_out_tag != 0 && tag != expected)
    violation("bTag " + std::to_string(tag) + " after " + std::to_string(s_.last_out_tag));
  s_.last_out_tag = tag;
  ut::Header h;
  std::copy_n(b.begin(), ut::kHeaderSize, h.begin());
  if (b[0] == 1) {  // DEV_DEP_MSG_OUT
    const std::uint32_t n = le32(&b[4]);
    if (n > b.size() - ut::kHeaderSize) return violation("TransferSize beyond the transfer");
    if (ut::wire_size(n) != b.size()) violation("DEV_DEP_MSG_OUT padding is not minimal");
    for (std::size_t i = ut::kHeaderSize + n; i < b.size(); ++i)
      if (b[i] != 0) violation("padding byte not zero");
    if (b[9] || b[10] || b[11]) violation("reserved bytes 9..11 not 0");
    s_.partial.append(reinterpret_cast<const char*>(&b[ut::kHeaderSize]), n);
    s_.log.push_back("out DEV_DEP_MSG_OUT" + std::string(b[8] & 1 ? " EOM" : ""));
    if (b[8] & ut::kAttrEom) {
      s_.messages.push_back(s_.partial);
      auto it = s_.replies.find(s_.partial);
      if (it != s_.replies.end()) s_.reply = it->second;
      s_.partial.clear();
    }
  } else if (b[0] == 2) {  // REQUEST_DEV_DEP_MSG_IN
    if (b.size() != ut::kHeaderSize) violation("REQUEST_DEV_DEP_MSG_IN longer than its header");
    if (b[10] || b[11]) violation("reserved bytes 10..11 not 0");
    s_.requests.push_back(h);
    s_.log.push_back("out REQUEST_DEV_DEP_MSG_IN");
    on_request(h);
  } else {
    violation("unknown MsgID " + std::to_string(b[0]));
  }
}

void FakeUsbTmcDevice::on_request(const ut::Header& h) {
  s_.last_request_tag = h[1];
  if (s_.silent || s_.reply.empty()) return;  // the host will time out
  std::size_t n = std::min<std::size_t>(s_.reply.size(), s_.cfg.max_reply_transfer);
  if (!s_.cfg.ignore_requested_size)
    n = std::min<std::size_t>(n, le32(&h[4]));
  else
    n = s_.reply.size();
  const std::string part = s_.reply.substr(0, n);
  s_.reply.erase(0, n);
  const std::uint8_t tag = s_.wrong_tag ? static_cast<std::uint8_t>(h[1] + 1) : h[1];
  queue_transfer(s_, tag, part, s_.reply.empty());
}

std::size_t FakeUsbTmcDevice::bulk_in(std::uint8_t* buf, std::size_t max,
                                      std::chrono::milliseconds) {
  s_.in_read_sizes.push_back(max);
  if (s_.stall_bulk_in) throw UsbIoError(UsbIoError::Code::Stall, "fake: bulk-IN stalled");
  if (s_.fifo.empty()) throw UsbIoError(UsbIoError::Code::Timeout, "fake: nothing to send");
  std::size_t got = 0;
  // As the host controller does: packets until the buffer is full or a short one ends it.
  while (!s_.fifo.empty()) {
    const std::vector<std::uint8_t>& p = s_.fifo.front();
    if (p.size() > max - got) throw UsbIoError(UsbIoError::Code::Io, "fake: overflow");
    if (!p.empty()) std::memcpy(buf + got, p.data(), p.size());  // a ZLP has no data()
    got += p.size();
    const bool short_packet = p.size() < s_.cfg.max_packet;
    s_.fifo.pop_front();
    if (short_packet || got == max) return got;
  }
  // Out of packets without a short one: a real read would block.
  throw UsbIoError(UsbIoError::Code::Timeout, "fake: transfer not terminated");
}

std::size_t FakeUsbTmcDevice::control_in(const ut::ControlSetup& c, std::uint8_t* buf,
                                         std::chrono::milliseconds) {
  using ut::Request;
  using ut::Status;
  s_.controls.push_back(c);
  const auto req = static_cast<Request>(c.request);
  s_.log.push_back("ctrl " + ut::to_string(req));
  const bool to_endpoint =
      req == Request::InitiateAbortBulkOut || req == Request::CheckAbortBulkOutStatus ||
      req == Request::InitiateAbortBulkIn || req == Request::CheckAbortBulkInStatus;
  const std::uint8_t want_type = to_endpoint ? ut::kToHostClassEndpoint : ut::kToHostClassInterface;
  const bool out_ep =
      req == Request::InitiateAbortBulkOut || req == Request::CheckAbortBulkOutStatus;
  const std::uint16_t want_index =
      to_endpoint ? (out_ep ? s_.cfg.ep_out : s_.cfg.ep_in) : s_.cfg.interface;
  if (c.request_type != want_type || c.index != want_index) {
    s_.violations.push_back("bad setup for " + ut::to_string(req));
    throw UsbIoError(UsbIoError::Code::Stall, "fake: control request stalled");
  }
  auto pop = [](std::deque<Status>& q, Status dflt) {
    if (q.empty()) return dflt;
    Status s = q.front();
    q.pop_front();
    return s;
  };
  std::memset(buf, 0, c.length);
  switch (req) {
    case Request::InitiateClear:
      s_.partial.clear();
      s_.reply.clear();
      if (!s_.keep_in_fifo_on_clear) s_.fifo.clear();
      buf[0] = static_cast<std::uint8_t>(s_.initiate_clear_status);
      return 1;
    case Request::CheckClearStatus: {
      const Status dflt = s_.fifo.empty() ? Status::Success : Status::Pending;
      buf[0] = static_cast<std::uint8_t>(pop(s_.check_clear_script, dflt));
      buf[1] = s_.fifo.empty() ? 0 : 1;
      return 2;
    }
    case Request::InitiateAbortBulkIn:
      if (c.value != s_.last_request_tag) {
        buf[0] = static_cast<std::uint8_t>(Status::TransferNotInProgress);
      } else {
        s_.reply.clear();
        s_.fifo.clear();
        s_.fifo.emplace_back();  // the short (zero-length) packet that ends the aborted transfer
        buf[0] = static_cast<std::uint8_t>(Status::Success);
      }
      buf[1] = static_cast<std::uint8_t>(c.value);
      return 2;
    case Request::CheckAbortBulkInStatus:
      buf[0] = static_cast<std::uint8_t>(pop(s_.check_abort_in_script, Status::Success));
      buf[1] = s_.fifo.empty() ? 0 : 1;
      return 8;
    case Request::InitiateAbortBulkOut:
      s_.partial.clear();
      buf[0] = static_cast<std::uint8_t>(Status::Success);
      buf[1] = static_cast<std::uint8_t>(c.value);
      return 2;
    case Request::CheckAbortBulkOutStatus:
      buf[0] = static_cast<std::uint8_t>(pop(s_.check_abort_out_script, Status::Success));
      return 8;
    default:
      throw UsbIoError(UsbIoError::Code::Stall, "fake: unsupported control request");
  }
}

void FakeUsbTmcDevice::clear_halt(std::uint8_t endpoint) {
  s_.halts_cleared.push_back(endpoint);
  s_.log.push_back("clear_halt " + std::to_string(endpoint));
}

}  // namespace piezo::testing
