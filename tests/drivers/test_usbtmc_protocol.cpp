// USBTMC framing (pure functions) and UsbTmcTransport over FakeUsbTmcDevice:
// header bytes, bTag wrap, splitting and padding, reassembly over transfers
// and packets, bad headers, timeouts with abort, clear with PENDING polling.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "drivers/usbtmc/usbtmc_protocol.hpp"
#include "drivers/usbtmc/usbtmc_quirks.hpp"
#include "drivers/usbtmc/usbtmc_transport.hpp"
#include "tests/drivers/fake_usbtmc_device.hpp"

namespace ut = piezo::drivers::usbtmc;
using piezo::drivers::TransportError;
using piezo::drivers::UsbTmcOptions;
using piezo::drivers::UsbTmcTransport;
using piezo::testing::FakeUsbTmcDevice;
using Bytes = std::vector<std::uint8_t>;

namespace {

Bytes bytes_of(const std::string& s) { return Bytes(s.begin(), s.end()); }

// A deterministic reply of n printable bytes.
std::string pattern(std::size_t n) {
  std::string s(n, ' ');
  for (std::size_t i = 0; i < n; ++i) s[i] = static_cast<char>('A' + i % 26);
  return s;
}

struct Bench {
  FakeUsbTmcDevice::State dev;
  std::unique_ptr<UsbTmcTransport> t;

  explicit Bench(FakeUsbTmcDevice::Config cfg = {}, UsbTmcOptions opts = fast()) {
    dev.cfg = cfg;
    t = std::make_unique<UsbTmcTransport>(std::make_unique<FakeUsbTmcDevice>(dev),
                                          "usbtmc://f00d:0001", opts);
  }
  static UsbTmcOptions fast() {
    UsbTmcOptions o;
    o.timeout = std::chrono::milliseconds(50);  // the fake never waits; no real time passes
    o.sequences.poll_interval = std::chrono::milliseconds(0);
    return o;
  }
  // Reads until EOM; returns the message and the chunk sizes with their EOM flags.
  std::string read_message(std::size_t chunk = 4096, std::vector<bool>* eoms = nullptr) {
    std::string out;
    std::vector<std::uint8_t> buf(chunk);
    for (int guard = 0; guard < 100000; ++guard) {
      bool eom = false;
      const std::size_t n = t->receive(buf.data(), buf.size(), &eom);
      out.append(reinterpret_cast<const char*>(buf.data()), n);
      if (eoms) eoms->push_back(eom);
      if (eom) return out;
    }
    ADD_FAILURE() << "no EOM";
    return out;
  }
  std::size_t count_controls(ut::Request r) const {
    return static_cast<std::size_t>(std::count_if(
        dev.controls.begin(), dev.controls.end(),
        [&](const ut::ControlSetup& c) { return c.request == static_cast<std::uint8_t>(r); }));
  }
};

TransportError::Kind kind_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const TransportError& e) {
    return e.kind();
  }
  ADD_FAILURE() << "no TransportError thrown";
  return TransportError::Kind::Closed;
}

}  // namespace

// ---- Pure framing ----

TEST(UsbTmcProtocol, DevDepMsgOutHeaderByteByByte) {
  const ut::Header h = ut::encode_dev_dep_msg_out(0x05, 0x01020304, true);
  const ut::Header want{0x01, 0x05, 0xFA, 0x00, 0x04, 0x03, 0x02, 0x01, 0x01, 0x00, 0x00, 0x00};
  EXPECT_EQ(h, want);
  EXPECT_EQ(ut::encode_dev_dep_msg_out(0x80, 7, false)[8], 0x00);  // no EOM
  EXPECT_EQ(ut::encode_dev_dep_msg_out(0x80, 7, false)[2], 0x7F);
}

TEST(UsbTmcProtocol, RequestDevDepMsgInHeaderByteByByte) {
  const ut::Header plain = ut::encode_request_dev_dep_msg_in(0xFF, 1u << 20, std::nullopt);
  const ut::Header want{0x02, 0xFF, 0x00, 0x00, 0x00, 0x00, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00};
  EXPECT_EQ(plain, want);
  const ut::Header term = ut::encode_request_dev_dep_msg_in(1, 64, std::uint8_t{'\n'});
  EXPECT_EQ(term[8], 0x02);  // TermCharEnabled
  EXPECT_EQ(term[9], '\n');
  EXPECT_THROW(ut::encode_dev_dep_msg_out(0, 1, true), std::invalid_argument);
}

TEST(UsbTmcProtocol, TagWrapsFrom255To1AndIsNeverZero) {
  ut::TagCounter tags;
  EXPECT_EQ(tags.next(), 1);
  std::uint8_t prev = 1;
  for (int i = 0; i < 600; ++i) {
    const std::uint8_t t = tags.next();
    ASSERT_NE(t, 0);
    ASSERT_EQ(t, prev == 255 ? 1 : prev + 1);
    prev = t;
  }
}

TEST(UsbTmcProtocol, SplitsAtMaxTransferPadsAndSetsEomOnlyOnLast) {
  const std::string msg = pattern(5000);
  ut::TagCounter tags;
  const auto ts = ut::frame_message(bytes_of(msg), tags, 2048);
  ASSERT_EQ(ts.size(), 3u);  // 2036 + 2036 + 928 payload bytes
  std::string joined;
  for (std::size_t i = 0; i < ts.size(); ++i) {
    const Bytes& t = ts[i];
    EXPECT_LE(t.size(), 2048u);
    EXPECT_EQ(t.size() % 4, 0u);
    EXPECT_EQ(t[1], i + 1);  // bTag per transfer
    EXPECT_EQ(t[8], i + 1 == ts.size() ? 1 : 0) << "EOM only on the last transfer";
    const std::uint32_t n = t[4] | t[5] << 8 | t[6] << 16 | t[7] << 24;
    joined.append(t.begin() + 12, t.begin() + 12 + n);
  }
  EXPECT_EQ(joined, msg);

  const auto odd = ut::frame_message(bytes_of("*RST\n"), tags, 2048);  // 5 bytes -> 17 -> 20
  ASSERT_EQ(odd.size(), 1u);
  EXPECT_EQ(odd[0].size(), 20u);
  EXPECT_EQ(odd[0][17], 0);
  EXPECT_EQ(odd[0][18], 0);
  EXPECT_EQ(odd[0][19], 0);
  EXPECT_EQ(ut::frame_message({}, tags, 2048).at(0).size(), 12u);  // empty message: header only
  EXPECT_THROW(ut::frame_message(bytes_of("x"), tags, 14), std::invalid_argument);
}

TEST(UsbTmcProtocol, BulkInHeaderValidation) {
  const Bytes good{0x02, 7, 0xF8, 0, 5, 0, 0, 0, 0x01, 0, 0, 0};
  const ut::BulkInHeader h = ut::parse_dev_dep_msg_in(good, 7, 100);
  EXPECT_EQ(h.transfer_size, 5u);
  EXPECT_TRUE(h.eom);
  auto bad = [&](std::size_t at, std::uint8_t v) {
    Bytes b = good;
    b[at] = v;
    return kind_of([&] { ut::parse_dev_dep_msg_in(b, 7, 100); });
  };
  EXPECT_EQ(bad(0, 0x01), TransportError::Kind::Protocol);  // MsgID
  EXPECT_EQ(bad(1, 8), TransportError::Kind::Protocol);     // bTag
  EXPECT_EQ(bad(2, 0xF7), TransportError::Kind::Protocol);  // ~bTag
  EXPECT_EQ(bad(4, 101), TransportError::Kind::Protocol);   // more than requested
  EXPECT_EQ(kind_of([&] { ut::parse_dev_dep_msg_in(std::span(good).first(11), 7, 100); }),
            TransportError::Kind::Protocol);
}

TEST(UsbTmcProtocol, PacketsAndReadSizes) {
  EXPECT_EQ(ut::packet_sizes(100, 64), (std::vector<std::size_t>{64, 36}));
  EXPECT_EQ(ut::packet_sizes(128, 64), (std::vector<std::size_t>{64, 64, 0}));  // ZLP
  EXPECT_EQ(ut::packet_sizes(12, 64), (std::vector<std::size_t>{12}));
  EXPECT_EQ(ut::bulk_in_read_size(100, 64, 4096), 128u);
  EXPECT_EQ(ut::bulk_in_read_size(128, 64, 4096), 192u);  // room for the terminating ZLP
  EXPECT_EQ(ut::bulk_in_read_size(100000, 64, 4096), 4096u);
}

TEST(UsbTmcProtocol, ClassRequestSetupsAndReplies) {
  const ut::ControlSetup a = ut::initiate_abort_bulk_in(9, 0x81);
  EXPECT_EQ(a.request_type, 0xA2);
  EXPECT_EQ(a.request, 3);
  EXPECT_EQ(a.value, 9);
  EXPECT_EQ(a.index, 0x81);
  EXPECT_EQ(a.length, 2);
  const ut::ControlSetup c = ut::check_clear_status(0);
  EXPECT_EQ(c.request_type, 0xA1);
  EXPECT_EQ(c.request, 6);
  EXPECT_EQ(c.length, 2);
  EXPECT_EQ(ut::initiate_clear(0).length, 1);
  EXPECT_EQ(ut::check_abort_bulk_out_status(0x02).length, 8);
  const Bytes r{0x02, 0x01, 0, 0, 0x10, 0, 0, 0};
  const ut::ClassReply cr = ut::parse_class_reply(ut::Request::CheckAbortBulkInStatus, r);
  EXPECT_EQ(cr.status, ut::Status::Pending);
  EXPECT_TRUE(cr.in_fifo_has_data);
  EXPECT_EQ(cr.nbytes, 16u);
  EXPECT_EQ(kind_of([&] {
              ut::parse_class_reply(ut::Request::CheckAbortBulkInStatus, std::span(r).first(2));
            }),
            TransportError::Kind::Protocol);
}

// ---- Transport over the fake device ----

TEST(UsbTmcTransport, QueryRoundTrip) {
  Bench b;
  b.dev.replies["*IDN?\n"] = "PIEZO,FAKE,0,1.0\n";
  b.t->send(std::string("*IDN?\n"));
  EXPECT_EQ(b.read_message(), "PIEZO,FAKE,0,1.0\n");
  EXPECT_EQ(b.dev.messages, std::vector<std::string>{"*IDN?\n"});
  ASSERT_EQ(b.dev.requests.size(), 1u);
  EXPECT_EQ(b.dev.requests[0][1], 2);  // request bTag follows the message's
  EXPECT_TRUE(b.dev.violations.empty()) << b.dev.violations.front();
}

TEST(UsbTmcTransport, TagsWrapAcrossManyTransfers) {
  Bench b;
  for (int i = 0; i < 300; ++i) b.t->send(std::string("X\n"));
  ASSERT_EQ(b.dev.out_transfers.size(), 300u);
  EXPECT_EQ(b.dev.out_transfers[254][1], 255);
  EXPECT_EQ(b.dev.out_transfers[255][1], 1);  // 255 -> 1, never 0
  EXPECT_TRUE(b.dev.violations.empty()) << b.dev.violations.front();
}

TEST(UsbTmcTransport, LongMessageIsSplitIntoTransfers) {
  UsbTmcOptions o = Bench::fast();
  o.max_out_transfer = 256;
  Bench b({}, o);
  const std::string msg = ":DATA:ARB " + pattern(1001) + "\n";
  b.t->send(msg);
  EXPECT_EQ(b.dev.messages, std::vector<std::string>{msg});
  EXPECT_EQ(b.dev.out_transfers.size(), (msg.size() + 243) / 244);
  for (const Bytes& t : b.dev.out_transfers) EXPECT_LE(t.size(), 256u);
  EXPECT_EQ(std::count(b.dev.log.begin(), b.dev.log.end(), "out DEV_DEP_MSG_OUT EOM"), 1);
  EXPECT_EQ(b.dev.log.back(), "out DEV_DEP_MSG_OUT EOM");
  EXPECT_TRUE(b.dev.violations.empty()) << b.dev.violations.front();
}

TEST(UsbTmcTransport, ReassemblesReplyOverSeveralTransfers) {
  FakeUsbTmcDevice::Config cfg;
  cfg.max_reply_transfer = 100;  // the device sends 1000 bytes as 10 transfers
  Bench b(cfg);
  const std::string reply = pattern(999) + "\n";
  b.dev.replies["WAV?\n"] = reply;
  b.t->send(std::string("WAV?\n"));
  std::vector<bool> eoms;
  EXPECT_EQ(b.read_message(37, &eoms), reply);  // odd caller buffer: chunks cut mid-transfer
  EXPECT_EQ(b.dev.requests.size(), 10u);        // one REQUEST_DEV_DEP_MSG_IN per transfer
  EXPECT_EQ(std::count(eoms.begin(), eoms.end(), true), 1);
  EXPECT_TRUE(eoms.back());
  EXPECT_TRUE(b.dev.violations.empty()) << b.dev.violations.front();
}

TEST(UsbTmcTransport, OneTransferSpansManyBulkInReads) {
  UsbTmcOptions o = Bench::fast();
  o.max_in_read = 128;  // two packets per read
  Bench b({}, o);
  const std::string reply = pattern(1500) + "\n";
  b.dev.replies["WAV?\n"] = reply;
  b.t->send(std::string("WAV?\n"));
  EXPECT_EQ(b.read_message(), reply);
  EXPECT_EQ(b.dev.requests.size(), 1u);
  EXPECT_GE(b.dev.in_read_sizes.size(), 12u);
  for (std::size_t n : b.dev.in_read_sizes) {
    EXPECT_EQ(n % 64, 0u) << "reads are whole packets";
    EXPECT_LE(n, 128u);
  }
  EXPECT_TRUE(b.dev.fifo.empty());
}

TEST(UsbTmcTransport, ZeroLengthPacketAfterFullPacketsIsConsumed) {
  Bench b;
  // 12 + 52 = 64 bytes: exactly one full packet, so the device ends with a ZLP.
  const std::string r1 = pattern(51) + "\n";
  b.dev.replies["A?\n"] = r1;
  b.dev.replies["B?\n"] = "second\n";
  b.t->send(std::string("A?\n"));
  EXPECT_EQ(b.read_message(), r1);
  EXPECT_TRUE(b.dev.fifo.empty()) << "ZLP left in the FIFO";
  b.t->send(std::string("B?\n"));
  EXPECT_EQ(b.read_message(), "second\n");
}

TEST(UsbTmcTransport, ZeroLengthPacketInItsOwnReadIsConsumedBeforeTheNextRequest) {
  UsbTmcOptions o = Bench::fast();
  o.max_in_read = 64;  // one packet per read: the ZLP cannot ride along with the data
  Bench b({}, o);
  const std::string r1 = pattern(115) + "\n";  // 12 + 116 = 128 = two full packets, then a ZLP
  b.dev.replies["A?\n"] = r1;
  b.dev.replies["B?\n"] = "second\n";
  for (int i = 0; i < 3; ++i) {
    b.t->send(std::string("A?\n"));
    EXPECT_EQ(b.read_message(), r1);
    b.t->send(std::string("B?\n"));
    EXPECT_EQ(b.read_message(), "second\n");
  }
  for (std::size_t n : b.dev.in_read_sizes) EXPECT_EQ(n, 64u);
}

TEST(UsbTmcTransport, TinyPacketsSplitTheHeader) {
  FakeUsbTmcDevice::Config cfg;
  cfg.max_packet = 8;  // full-speed minimum: the 12-byte header spans two packets
  Bench b(cfg);
  for (std::size_t n : {1u, 4u, 19u, 20u, 100u}) {
    const std::string reply = pattern(n);
    b.dev.replies["Q?\n"] = reply;
    b.t->send(std::string("Q?\n"));
    EXPECT_EQ(b.read_message(5), reply) << n;
  }
  EXPECT_TRUE(b.dev.violations.empty()) << b.dev.violations.front();
}

TEST(UsbTmcTransport, EmptyTransferWithEomEndsTheMessage) {
  Bench b;
  b.t->send(std::string("X\n"));  // tag 1; the request below gets tag 2
  FakeUsbTmcDevice::queue_transfer(b.dev, 2, "", true);
  std::uint8_t buf[8];
  bool eom = false;
  EXPECT_EQ(b.t->receive(buf, sizeof buf, &eom), 0u);
  EXPECT_TRUE(eom);
}

TEST(UsbTmcTransport, WrongTagIsAProtocolErrorAndTheNextQueryWorks) {
  Bench b;
  b.dev.replies["*IDN?\n"] = "PIEZO,FAKE\n";
  b.dev.wrong_tag = true;
  b.t->send(std::string("*IDN?\n"));
  std::uint8_t buf[64];
  bool eom = false;
  EXPECT_EQ(kind_of([&] { b.t->receive(buf, sizeof buf, &eom); }), TransportError::Kind::Protocol);
  b.dev.wrong_tag = false;
  b.t->send(std::string("*IDN?\n"));
  EXPECT_EQ(b.read_message(), "PIEZO,FAKE\n");
}

TEST(UsbTmcTransport, TimeoutRunsAbortBulkInThenThrowsTimeout) {
  Bench b;
  b.dev.silent = true;
  b.dev.check_abort_in_script = {ut::Status::Pending, ut::Status::Pending};
  b.t->send(std::string("MEAS?\n"));
  std::uint8_t buf[64];
  bool eom = false;
  try {
    b.t->receive(buf, sizeof buf, &eom);
    FAIL() << "no timeout";
  } catch (const TransportError& e) {
    EXPECT_EQ(e.kind(), TransportError::Kind::Timeout);
    EXPECT_NE(std::string(e.what()).find("usbtmc://f00d:0001"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("aborted"), std::string::npos) << e.what();
  }
  ASSERT_EQ(b.count_controls(ut::Request::InitiateAbortBulkIn), 1u);
  const auto init = std::find_if(b.dev.controls.begin(), b.dev.controls.end(), [](auto& c) {
    return c.request == static_cast<std::uint8_t>(ut::Request::InitiateAbortBulkIn);
  });
  EXPECT_EQ(init->value, b.dev.requests.back()[1]) << "abort names the request's bTag";
  EXPECT_EQ(init->index, 0x81);
  EXPECT_EQ(b.count_controls(ut::Request::CheckAbortBulkInStatus),
            3u);  // PENDING, PENDING, SUCCESS
  EXPECT_TRUE(b.dev.fifo.empty()) << "the aborted transfer's short packet was read";

  b.dev.silent = false;  // the transport is usable afterwards
  b.dev.replies["MEAS?\n"] = "1.5\n";
  b.t->send(std::string("MEAS?\n"));
  EXPECT_EQ(b.read_message(), "1.5\n");
}

TEST(UsbTmcTransport, BulkOutTimeoutAbortsAndClearsHalt) {
  Bench b;
  b.dev.bulk_out_times_out = true;
  b.dev.check_abort_out_script = {ut::Status::Pending};
  EXPECT_EQ(kind_of([&] { b.t->send(std::string("*RST\n")); }), TransportError::Kind::Timeout);
  EXPECT_EQ(b.count_controls(ut::Request::InitiateAbortBulkOut), 1u);
  EXPECT_EQ(b.count_controls(ut::Request::CheckAbortBulkOutStatus), 2u);
  EXPECT_EQ(b.dev.halts_cleared, std::vector<std::uint8_t>{0x02});
}

TEST(UsbTmcTransport, StallClearsTheHaltAndReportsIo) {
  Bench b;
  b.dev.replies["Q?\n"] = "1\n";
  b.t->send(std::string("Q?\n"));
  b.dev.stall_bulk_in = true;
  std::uint8_t buf[8];
  bool eom = false;
  EXPECT_EQ(kind_of([&] { b.t->receive(buf, sizeof buf, &eom); }), TransportError::Kind::Io);
  EXPECT_EQ(b.dev.halts_cleared, std::vector<std::uint8_t>{0x81});
}

TEST(UsbTmcTransport, ClearPollsWhilePendingThenClearsBulkOutHalt) {
  Bench b;
  b.dev.check_clear_script = {ut::Status::Pending, ut::Status::Pending, ut::Status::Pending};
  b.t->clear();
  EXPECT_EQ(b.count_controls(ut::Request::InitiateClear), 1u);
  EXPECT_EQ(b.count_controls(ut::Request::CheckClearStatus), 4u);
  const std::vector<std::string> want{"ctrl INITIATE_CLEAR",     "ctrl CHECK_CLEAR_STATUS",
                                      "ctrl CHECK_CLEAR_STATUS", "ctrl CHECK_CLEAR_STATUS",
                                      "ctrl CHECK_CLEAR_STATUS", "clear_halt 2"};
  EXPECT_EQ(b.dev.log, want);
}

TEST(UsbTmcTransport, ClearDrainsStaleInputThenQueriesWork) {
  Bench b;
  b.dev.keep_in_fifo_on_clear = true;
  b.dev.replies["WAV?\n"] = pattern(300);
  b.dev.replies["*OPC?\n"] = "1\n";
  b.t->send(std::string("WAV?\n"));
  std::uint8_t buf[16];
  bool eom = false;
  b.t->receive(buf, sizeof buf, &eom);  // read a little, abandon the rest
  b.t->clear();                         // device reports PENDING + data until drained
  EXPECT_TRUE(b.dev.fifo.empty());
  b.t->send(std::string("*OPC?\n"));
  EXPECT_EQ(b.read_message(), "1\n");
}

TEST(UsbTmcTransport, ClearRefusedIsAProtocolError) {
  Bench b;
  b.dev.initiate_clear_status = ut::Status::Failed;
  EXPECT_EQ(kind_of([&] { b.t->clear(); }), TransportError::Kind::Protocol);
  b.dev.initiate_clear_status = ut::Status::Success;
  b.dev.check_clear_script.assign(1000, ut::Status::Pending);  // never finishes
  EXPECT_EQ(kind_of([&] { b.t->clear(); }), TransportError::Kind::Timeout);
}

TEST(UsbTmcTransport, TermCharIsRequestedWhenConfigured) {
  UsbTmcOptions o = Bench::fast();
  o.term_char = '\n';
  Bench b({}, o);
  b.dev.replies["Q?\n"] = "1\n";
  b.t->send(std::string("Q?\n"));
  EXPECT_EQ(b.read_message(), "1\n");
  EXPECT_EQ(b.dev.requests.at(0)[8], 0x02);
  EXPECT_EQ(b.dev.requests.at(0)[9], '\n');
}

// ---- Quirks ----

TEST(UsbTmcQuirks, TableEntriesAreDocumentedAndApplied) {
  for (const ut::UsbTmcQuirk& q : ut::quirk_table()) {
    EXPECT_NE(std::string(q.model), "");
    EXPECT_NE(std::string(q.source), "") << q.model;
  }
  EXPECT_NE(ut::find_quirk(0x1ab1, 0x0588), nullptr);
  EXPECT_EQ(ut::find_quirk(0x0957, 0x2807), nullptr);
  UsbTmcOptions o;
  EXPECT_EQ(piezo::drivers::with_quirks(o, 0x1ab1, 0x0588).in_request_size,
            piezo::drivers::kWholeMessageRequest);
  EXPECT_EQ(piezo::drivers::with_quirks(o, 0x0957, 0x2807).in_request_size, o.in_request_size);
}

TEST(UsbTmcQuirks, WholeMessageDeviceNeedsTheQuirk) {
  FakeUsbTmcDevice::Config cfg;
  cfg.ignore_requested_size = true;  // Rigol-like: whole reply regardless of TransferSize
  UsbTmcOptions o = Bench::fast();
  o.in_request_size = 256;
  const std::string reply = pattern(2000) + "\n";
  {
    Bench b(cfg, o);
    b.dev.replies["WAV?\n"] = reply;
    b.t->send(std::string("WAV?\n"));
    std::uint8_t buf[64];
    bool eom = false;
    EXPECT_EQ(kind_of([&] { b.t->receive(buf, sizeof buf, &eom); }),
              TransportError::Kind::Protocol);
  }
  Bench b(cfg, piezo::drivers::with_quirks(o, 0x1ab1, 0x0588));
  b.dev.replies["WAV?\n"] = reply;
  b.t->send(std::string("WAV?\n"));
  EXPECT_EQ(b.read_message(), reply);
  EXPECT_EQ(b.dev.requests.size(), 1u);
}
