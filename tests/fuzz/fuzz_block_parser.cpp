// Fuzz harness: IEEE 488.2 definite-length blocks and the SCPI byte plumbing.
// The input is an instrument byte stream, read five ways:
//   1. parse_block_header on the stream (drivers/ieee488_block.hpp);
//   2. the server-side InputFramer (drivers/scpi_parse.hpp), fed whole and in
//      fuzz-chosen pieces: framing must not depend on how TCP cut the bytes;
//   3. split_commands / parse_command / match of every framed message against
//      the header patterns the simulated instruments use;
//   4. ScpiClient (drivers/scpi_client.hpp) reading the stream as an
//      instrument's replies to a fuzz-chosen sequence of queries;
//   5. the USBTMC bulk-IN header and class-request reply parsers.
// Documented rejections: std::invalid_argument from parse_block_header,
// InstrumentError / TransportError from the client, TransportError(Protocol)
// from the USBTMC parsers. Anything else is a finding.
#include <algorithm>
#include <cstdint>
#include <deque>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "drivers/ieee488_block.hpp"
#include "drivers/scpi_client.hpp"
#include "drivers/scpi_parse.hpp"
#include "drivers/transport.hpp"
#include "drivers/usbtmc/usbtmc_protocol.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace piezo::drivers;
using piezo::fuzz::ByteReader;
using Bytes = std::vector<std::uint8_t>;

// ------------------------------------------------------------ 1. block header
void check_block_header(std::span<const std::uint8_t> s) {
  std::optional<BlockHeader> h;
  try {
    h = parse_block_header(s);
  } catch (const std::invalid_argument&) {
    return;  // malformed: documented
  }
  if (!h) {  // "need more bytes": only a true prefix of a header may say so
    FUZZ_CHECK(s.size() < 2 || (s[1] >= '1' && s[1] <= '9' && s.size() < 2u + (s[1] - '0')),
               "nullopt for a %zu-byte input that holds a whole header", s.size());
    return;
  }
  const std::size_t n = s[1] - '0';
  FUZZ_CHECK(s[0] == '#' && n >= 1 && n <= 9 && h->header_len == 2 + n,
             "header_len %zu for '#%c'", h->header_len, s[1]);
  std::size_t len = 0;
  for (std::size_t i = 0; i < n; ++i) len = len * 10 + (s[2 + i] - '0');
  FUZZ_CHECK(h->payload_len == len, "payload_len %zu, digits say %zu", h->payload_len, len);
  // Round trip through the encoder (shortest header for the same length).
  const std::string enc = block_header(len);
  auto back = parse_block_header(std::span<const std::uint8_t>(
      reinterpret_cast<const std::uint8_t*>(enc.data()), enc.size()));
  FUZZ_CHECK(back && back->payload_len == len && back->header_len == enc.size(),
             "block_header(%zu) = '%s' does not parse back", len, enc.c_str());
}

// ------------------------------------------------------------ 2./3. server side
struct Msg {
  std::string text;
  Bytes block;
  bool has_block;
  bool operator==(const Msg&) const = default;
};

std::vector<Msg> frame(std::span<const std::uint8_t> s, const std::vector<std::size_t>& cuts) {
  scpi::InputFramer f;
  std::vector<Msg> out;
  std::size_t pos = 0;
  for (std::size_t k = 0; k <= cuts.size(); ++k) {
    const std::size_t end = k < cuts.size() ? std::min(s.size(), pos + cuts[k]) : s.size();
    f.feed(s.subspan(pos, end - pos));
    pos = end;
    while (auto m = f.next()) out.push_back({m->text, m->block, m->has_block});
  }
  return out;
}

const char* const kPatterns[] = {
    "SYSTem:ERRor[:NEXT]", "[SOURce#:]FUNCtion:ARBitrary:SRATe", "[SOURce#:]VOLTage[:AMPLitude]",
    "[SOURce#:]DATA:ARBitrary", "OUTPut#[:STATe]", "TRIGger#:SOURce", "CHANnel#:RANGe",
    "CHANnel#", ":ACQuire:POINts[:ANALog]", "ACQuire:SRATe[:ANALog]", "WAVeform:DATA",
    "SIMulation:DUT", "FORMat:BORDer"};

std::size_t suffix_nodes(const std::string& p) { return static_cast<std::size_t>(std::count(p.begin(), p.end(), '#')); }

void check_commands(const Msg& m) {
  if (!m.has_block)
    FUZZ_CHECK(m.text.find('\n') == std::string::npos, "framed text holds a newline");
  if (m.has_block) {  // a '#' inside a quoted string is text, never a block
    char quote = 0;
    for (char ch : m.text)
      if (quote ? ch == quote : (ch == '"' || ch == '\''))
        quote = quote ? 0 : ch;
    FUZZ_CHECK(quote == 0, "a block started inside a quoted string: '%s'", m.text.c_str());
  }
  auto parts = m.has_block ? std::vector<std::string>{m.text} : scpi::split_commands(m.text);
  for (const auto& text : parts) {
    const scpi::Command c = scpi::parse_command(text);
    FUZZ_CHECK(c.header.find_first_of(" \t") == std::string::npos, "header holds a blank");
    for (const auto& p : c.params)
      FUZZ_CHECK(p.empty() || (p.front() != ' ' && p.back() != ' '), "parameter not trimmed");
    for (const char* pat : kPatterns) {
      std::vector<int> sfx;
      const bool ok = scpi::match(pat, c.header, &sfx);  // documented: never throws
      FUZZ_CHECK(ok || sfx.empty(), "failed match leaves %zu suffixes", sfx.size());
      FUZZ_CHECK(sfx.size() <= suffix_nodes(pat), "%zu suffixes for '%s'", sfx.size(), pat);
      FUZZ_CHECK(ok == scpi::match(pat, c.header), "match differs with/without suffix output");
    }
    // A parameter that is a header (WAVeform:SOURce CHANnel2).
    if (!c.params.empty()) {
      std::vector<int> s;
      scpi::match("CHANnel#", c.params[0], &s);
    }
  }
}

void check_framer(ByteReader& ctl, std::span<const std::uint8_t> s) {
  std::vector<std::size_t> cuts;
  const std::size_t n_cuts = ctl.pick(8);
  for (std::size_t k = 0; k < n_cuts; ++k) cuts.push_back(ctl.pick(64));
  const auto whole = frame(s, {});
  const auto pieces = frame(s, cuts);
  FUZZ_CHECK(whole == pieces, "framing depends on packetisation: %zu messages whole, %zu in pieces",
             whole.size(), pieces.size());
  for (const auto& m : whole) check_commands(m);
}

// ------------------------------------------------------------ 4. client side
// A transport whose replies are the fuzz stream, handed out in fuzz-chosen
// pieces with fuzz-chosen end-of-message flags; past the end it times out.
class ScriptTransport final : public Transport {
 public:
  ScriptTransport(std::span<const std::uint8_t> s, std::vector<std::size_t> pieces, std::uint8_t eom_bits)
      : s_(s), pieces_(std::move(pieces)), eom_bits_(eom_bits) {}
  std::string address() const override { return "fuzz://script"; }
  void send(std::span<const std::uint8_t>) override {}
  std::size_t receive(std::uint8_t* buf, std::size_t max, bool* eom) override {
    if (pos_ >= s_.size()) throw TransportError(TransportError::Kind::Timeout, "fuzz://script: no reply");
    std::size_t n = pieces_.empty() ? s_.size() : pieces_[k_ % pieces_.size()];
    n = std::clamp<std::size_t>(n, 1, std::min(max, s_.size() - pos_));
    std::copy_n(s_.data() + pos_, n, buf);
    pos_ += n;
    *eom = pos_ == s_.size() || ((eom_bits_ >> (k_ % 8)) & 1);
    ++k_;
    return n;
  }
  void set_timeout(std::chrono::milliseconds) override {}
  std::chrono::milliseconds timeout() const override { return std::chrono::milliseconds(1); }
  using Transport::send;

 private:
  std::span<const std::uint8_t> s_;
  std::vector<std::size_t> pieces_;
  std::uint8_t eom_bits_;
  std::size_t pos_ = 0, k_ = 0;
};

void check_client(ByteReader& ctl, std::span<const std::uint8_t> s) {
  std::vector<std::size_t> pieces;
  const std::size_t np = ctl.pick(4);
  for (std::size_t k = 0; k < np; ++k) pieces.push_back(1 + ctl.pick(200));
  ScpiClient client(std::make_unique<ScriptTransport>(s, pieces, ctl.u8()));
  const std::size_t n_ops = 1 + ctl.pick(6);
  for (std::size_t k = 0; k < n_ops; ++k) {
    try {
      switch (ctl.pick(6)) {
        case 0: {
          const std::string r = client.query("*IDN?");
          FUZZ_CHECK(r.find('\n') == std::string::npos, "reply line holds its terminator");
          break;
        }
        case 1:
          client.query_double("ACQ:SRAT?");
          break;
        case 2: {
          const auto b = client.query_block("WAV:DATA?");
          FUZZ_CHECK(b.size() <= s.size(), "a %zu-byte block out of a %zu-byte stream", b.size(), s.size());
          break;
        }
        case 3:
          client.check_errors("fuzz");
          break;
        case 4:
          client.configure("ACQ:POIN 1000");
          break;
        default:
          client.identify();
          break;
      }
    } catch (const InstrumentError&) {
    } catch (const TransportError&) {
    }
  }
}

// ------------------------------------------------------------ 5. USBTMC
void check_usbtmc(ByteReader& ctl, std::span<const std::uint8_t> s) {
  namespace ut = usbtmc;
  const std::uint8_t tag = ctl.u8();
  const std::uint32_t requested = ctl.u32();
  try {
    const auto h = ut::parse_dev_dep_msg_in(s.first(std::min<std::size_t>(s.size(), ut::kHeaderSize)), tag, requested);
    FUZZ_CHECK(h.tag == tag && h.transfer_size <= requested, "bulk-IN header accepted out of bounds");
  } catch (const TransportError& e) {
    FUZZ_CHECK(e.kind() == TransportError::Kind::Protocol, "non-protocol TransportError");
  }
  for (int r = 1; r <= 7; ++r) {
    try {
      ut::parse_class_reply(static_cast<ut::Request>(r), s.first(std::min<std::size_t>(s.size(), ctl.pick(32))));
    } catch (const TransportError& e) {
      FUZZ_CHECK(e.kind() == TransportError::Kind::Protocol, "non-protocol TransportError");
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Layout: byte 0 = k (mod 32), then k control bytes (chunking, the query
  // sequence; missing ones read as 0), then the byte stream itself.
  const std::size_t k = size ? std::min<std::size_t>(data[0] % 32, size - 1) : 0;
  ByteReader ctl(size ? data + 1 : data, k);
  const std::span<const std::uint8_t> stream = size ? std::span(data + 1 + k, size - 1 - k)
                                                    : std::span<const std::uint8_t>();
  check_block_header(stream);
  check_framer(ctl, stream);
  check_client(ctl, stream);
  check_usbtmc(ctl, stream);
  return 0;
}
