#include "drivers/usbtmc/usbtmc_transport.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "drivers/usbtmc/libusb_endpoints.hpp"
#include "drivers/usbtmc/usbtmc_quirks.hpp"

namespace piezo::drivers {

using usbtmc::UsbIoError;

namespace {
// A device that keeps answering with empty, non-EOM transfers is broken;
// give up rather than spin.
constexpr int kMaxEmptyTransfers = 64;

std::string hex2(std::uint8_t v) {
  char b[8];
  std::snprintf(b, sizeof b, "0x%02x", v);
  return b;
}
}  // namespace

UsbTmcOptions with_quirks(UsbTmcOptions opts, std::uint16_t vid, std::uint16_t pid) {
  if (const usbtmc::UsbTmcQuirk* q = usbtmc::find_quirk(vid, pid)) {
    if (q->whole_message_per_request) opts.in_request_size = kWholeMessageRequest;
  }
  return opts;
}

UsbTmcTransport::UsbTmcTransport(std::unique_ptr<usbtmc::UsbTmcEndpoints> endpoints,
                                 std::string address, UsbTmcOptions opts)
    : ep_(std::move(endpoints)), address_(std::move(address)), opts_(std::move(opts)) {
  if (!ep_) throw std::invalid_argument("UsbTmcTransport: no endpoints");
  const std::size_t mps = ep_->max_packet_size();
  if (mps == 0) throw std::invalid_argument("UsbTmcTransport: wMaxPacketSize is 0");
  if (opts_.max_out_transfer % 4 != 0 || opts_.max_out_transfer < usbtmc::kHeaderSize + 4)
    throw std::invalid_argument("UsbTmcTransport: max_out_transfer must be a multiple of 4, >= 16");
  if (opts_.in_request_size == 0)
    throw std::invalid_argument("UsbTmcTransport: in_request_size must be > 0");
  opts_.max_in_read = std::max(mps, opts_.max_in_read / mps * mps);
  rx_.resize(opts_.max_in_read);
}

void UsbTmcTransport::fail(TransportError::Kind k, const std::string& what) {
  throw TransportError(k, address_ + ": " + what);
}

// Maps a USB failure to a TransportError; a stalled bulk endpoint gets its
// halt cleared first so the next command can go through (endpoint 0: none).
void UsbTmcTransport::fail(const UsbIoError& e, std::uint8_t endpoint, const char* during) {
  reset_input();
  switch (e.code()) {
    case UsbIoError::Code::Timeout:
      fail(TransportError::Kind::Timeout, std::string(during) + ": timed out");
    case UsbIoError::Code::Stall: {
      if (endpoint == 0) fail(TransportError::Kind::Io, std::string(during) + ": " + e.what());
      std::string note = "halt cleared";
      try {
        ep_->clear_halt(endpoint);
      } catch (const UsbIoError& e2) {
        note = std::string("clearing the halt failed: ") + e2.what();
      }
      fail(TransportError::Kind::Io,
           std::string(during) + ": endpoint " + hex2(endpoint) + " stalled (" + note + ")");
    }
    case UsbIoError::Code::NoDevice:
      fail(TransportError::Kind::Closed, std::string(during) + ": device disconnected");
    case UsbIoError::Code::Io:
      break;
  }
  fail(TransportError::Kind::Io, std::string(during) + ": " + e.what());
}

void UsbTmcTransport::send(std::span<const std::uint8_t> bytes) {
  const auto transfers = usbtmc::frame_message(bytes, tags_, opts_.max_out_transfer);
  for (const auto& t : transfers) {
    try {
      ep_->bulk_out(t, opts_.timeout);
    } catch (const UsbIoError& e) {
      if (e.code() != UsbIoError::Code::Timeout) fail(e, ep_->bulk_out_address(), "send");
      std::string outcome;
      try {
        outcome = usbtmc::run_abort_bulk_out(*ep_, t[1], opts_.sequences);
      } catch (const std::exception& e2) {
        outcome = std::string("abort failed: ") + e2.what();
      }
      fail(TransportError::Kind::Timeout, "send: device accepted no data within " +
                                              std::to_string(opts_.timeout.count()) + " ms (" +
                                              outcome + ")");
    }
  }
}

void UsbTmcTransport::reset_input() {
  win_begin_ = win_end_ = 0;
  open_ = false;
  header_bytes_ = 0;
  wire_got_ = payload_got_ = 0;
  zero_length_eom_ = false;
}

void UsbTmcTransport::start_transfer() {
  reset_input();
  request_tag_ = tags_.next();
  requested_ = opts_.in_request_size;
  const usbtmc::Header h =
      usbtmc::encode_request_dev_dep_msg_in(request_tag_, requested_, opts_.term_char);
  try {
    ep_->bulk_out(h, opts_.timeout);
  } catch (const UsbIoError& e) {
    if (e.code() != UsbIoError::Code::Timeout) fail(e, ep_->bulk_out_address(), "receive");
    std::string outcome;
    try {
      outcome = usbtmc::run_abort_bulk_out(*ep_, request_tag_, opts_.sequences);
    } catch (const std::exception& e2) {
      outcome = std::string("abort failed: ") + e2.what();
    }
    fail(TransportError::Kind::Timeout,
         "receive: REQUEST_DEV_DEP_MSG_IN not accepted (" + outcome + ")");
  }
  open_ = true;
}

// One bulk-IN read of the open transfer. The header may span reads (tiny
// packets), the payload may span many (long transfers); the transfer ends
// with the first short read.
void UsbTmcTransport::read_more() {
  const std::size_t mps = ep_->max_packet_size();
  const std::size_t expected =
      usbtmc::wire_size(header_bytes_ == usbtmc::kHeaderSize ? in_.transfer_size : requested_);
  const std::size_t left = expected > wire_got_ ? expected - wire_got_ : 0;
  const std::size_t want = usbtmc::bulk_in_read_size(left, mps, opts_.max_in_read);
  std::size_t n = 0;
  try {
    n = ep_->bulk_in(rx_.data(), want, opts_.timeout);
  } catch (const UsbIoError& e) {
    if (e.code() != UsbIoError::Code::Timeout) fail(e, ep_->bulk_in_address(), "receive");
    const std::uint8_t tag = request_tag_;
    reset_input();
    std::string outcome;
    try {
      outcome = usbtmc::run_abort_bulk_in(*ep_, tag, opts_.sequences);
    } catch (const std::exception& e2) {
      outcome = std::string("abort failed: ") + e2.what();
    }
    fail(TransportError::Kind::Timeout, "receive: no response within " +
                                            std::to_string(opts_.timeout.count()) + " ms (" +
                                            outcome + ")");
  }
  if (n > want) fail(TransportError::Kind::Io, "receive: bulk-IN read overflowed");
  const bool short_read = n < want;
  wire_got_ += n;
  // On a framing error, drop the rest of the device's transfer so the next
  // request starts clean, then report.
  auto protocol_error = [&](const std::string& what) {
    reset_input();
    if (!short_read) {
      try {
        usbtmc::drain_bulk_in(*ep_, opts_.sequences);
      } catch (const UsbIoError&) {
      }
    }
    fail(TransportError::Kind::Protocol, what);
  };

  std::size_t off = 0;
  if (header_bytes_ < usbtmc::kHeaderSize) {
    off = std::min(n, usbtmc::kHeaderSize - header_bytes_);
    std::memcpy(header_.data() + header_bytes_, rx_.data(), off);
    header_bytes_ += off;
    if (header_bytes_ == usbtmc::kHeaderSize) {
      try {
        in_ = usbtmc::parse_dev_dep_msg_in(header_, request_tag_, requested_);
      } catch (const TransportError& e) {
        protocol_error(e.what());
      }
    }
  }
  if (header_bytes_ == usbtmc::kHeaderSize) {
    const std::size_t take = std::min(n - off, in_.transfer_size - payload_got_);
    win_begin_ = off;
    win_end_ = off + take;
    payload_got_ += take;
    if (wire_got_ > usbtmc::wire_size(in_.transfer_size))
      protocol_error("USBTMC protocol error: device sent more bytes than its header announced");
  }
  if (!short_read) return;
  open_ = false;
  if (header_bytes_ < usbtmc::kHeaderSize || payload_got_ < in_.transfer_size) {
    const std::string what =
        header_bytes_ < usbtmc::kHeaderSize
            ? "transfer ended inside the bulk-IN header (" + std::to_string(wire_got_) + " bytes)"
            : "transfer ended after " + std::to_string(payload_got_) + " of " +
                  std::to_string(in_.transfer_size) + " bytes";
    protocol_error("USBTMC protocol error: " + what);
  }
  if (in_.transfer_size == 0 && in_.eom) zero_length_eom_ = true;
}

std::size_t UsbTmcTransport::receive(std::uint8_t* buf, std::size_t max, bool* end_of_message) {
  if (max == 0) throw std::invalid_argument("UsbTmcTransport::receive: max is 0");
  int empty_transfers = 0;
  for (;;) {
    if (win_begin_ < win_end_) {
      const std::size_t n = std::min(max, win_end_ - win_begin_);
      std::memcpy(buf, rx_.data() + win_begin_, n);
      win_begin_ += n;
      if (end_of_message)
        *end_of_message = win_begin_ == win_end_ && payload_got_ == in_.transfer_size && in_.eom;
      return n;
    }
    if (zero_length_eom_) {  // the message ended with an empty transfer
      zero_length_eom_ = false;
      if (end_of_message) *end_of_message = true;
      return 0;
    }
    if (!open_) {
      if (++empty_transfers > kMaxEmptyTransfers)
        fail(TransportError::Kind::Protocol,
             "USBTMC protocol error: device keeps sending empty transfers without EOM");
      start_transfer();
    }
    read_more();
  }
}

void UsbTmcTransport::clear() {
  reset_input();
  try {
    usbtmc::run_clear(*ep_, opts_.sequences);
  } catch (const UsbIoError& e) {
    fail(e, 0, "clear");
  } catch (const TransportError& e) {
    fail(e.kind(), std::string("clear: ") + e.what());
  }
}

std::unique_ptr<UsbTmcTransport> open_usbtmc(const InstrumentUri& uri, UsbTmcOptions opts) {
  if (uri.kind != InstrumentUri::Kind::UsbTmc)
    throw std::invalid_argument("open_usbtmc: '" + uri.to_string() +
                                "' is not a usbtmc:// address");
  auto ep = usbtmc::LibusbEndpoints::open(uri.vid, uri.pid, uri.serial, uri.to_string());
  return std::make_unique<UsbTmcTransport>(std::move(ep), uri.to_string(),
                                           with_quirks(std::move(opts), uri.vid, uri.pid));
}

}  // namespace piezo::drivers
