#include "drivers/scpi_client.hpp"

#include <algorithm>
#include <charconv>
#include <cstdlib>

#include "drivers/ieee488_block.hpp"

namespace piezo::drivers {

void with_step_prefix(const std::string& prefix, const std::function<void()>& f) {
  try {
    f();
  } catch (const InstrumentError& e) {
    throw InstrumentError(prefix + e.what());
  } catch (const TransportError& e) {
    throw TransportError(e.kind(), prefix + e.what());
  }
}

ScpiClient::ScpiClient(std::unique_ptr<Transport> t) : t_(std::move(t)) {
  if (!t_) throw std::invalid_argument("ScpiClient: null transport");
  address_ = t_->address();
}

void ScpiClient::write(const std::string& cmd) { t_->send(cmd + "\n"); }

std::size_t ScpiClient::read_some(std::uint8_t* buf, std::size_t max, bool* eom) {
  if (!pending_.empty()) {
    std::size_t n = std::min(max, pending_.size());
    std::copy_n(pending_.begin(), n, buf);
    pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(n));
    *eom = pending_.empty() && pending_eom_;
    if (pending_.empty()) pending_eom_ = false;
    return n;
  }
  return t_->receive(buf, max, eom);
}

std::string ScpiClient::read_line() {
  std::string line;
  std::uint8_t buf[4096];
  for (;;) {
    bool eom = false;
    std::size_t n = read_some(buf, sizeof buf, &eom);
    auto* nl = std::find(buf, buf + n, static_cast<std::uint8_t>('\n'));
    line.append(reinterpret_cast<char*>(buf), reinterpret_cast<char*>(nl));
    if (nl != buf + n) {  // keep what follows the terminator
      pending_.insert(pending_.begin(), nl + 1, buf + n);
      pending_eom_ = eom && !pending_.empty();
      break;
    }
    if (eom) break;
    if (line.size() > (1u << 20))
      throw InstrumentError(address_ + ": response line longer than 1 MiB without a terminator");
  }
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return line;
}

void ScpiClient::read_exact(std::uint8_t* buf, std::size_t n) {
  std::size_t got = 0;
  while (got < n) {
    bool eom = false;
    std::size_t k = read_some(buf + got, n - got, &eom);
    got += k;
    if (eom && got < n)
      throw InstrumentError(address_ + ": binary block truncated: got " + std::to_string(got) +
                            " of " + std::to_string(n) + " bytes");
  }
}

std::string ScpiClient::query(const std::string& cmd) {
  write(cmd);
  try {
    return read_line();
  } catch (const TransportError& e) {
    throw TransportError(e.kind(), std::string(e.what()) + " (waiting for the reply to '" + cmd + "')");
  }
}

double ScpiClient::query_double(const std::string& cmd) {
  std::string r = query(cmd);
  char* end = nullptr;
  double v = std::strtod(r.c_str(), &end);
  if (r.empty() || end == r.c_str())
    throw InstrumentError(address_ + ": '" + cmd + "' answered '" + r + "', expected a number");
  return v;
}

std::vector<std::uint8_t> ScpiClient::query_block(const std::string& cmd) {
  write(cmd);
  std::vector<std::uint8_t> head;
  std::optional<BlockHeader> h;
  try {
    while (!h) {
      std::uint8_t c;
      read_exact(&c, 1);
      head.push_back(c);
      h = parse_block_header(head);
    }
  } catch (const std::invalid_argument& e) {
    throw InstrumentError(address_ + ": malformed binary block in reply to '" + cmd + "': " + e.what());
  } catch (const TransportError& e) {
    throw TransportError(e.kind(), std::string(e.what()) + " (reading the block of '" + cmd + "')");
  }
  // The header's length is the instrument's word, not yet data: grow the
  // buffer as bytes arrive (64 KiB at a time), so a corrupt "#9999999999"
  // costs what was received, not a gigabyte up front.
  constexpr std::size_t kStep = std::size_t{1} << 16;
  std::vector<std::uint8_t> payload;
  payload.reserve(std::min(h->payload_len, kStep));
  try {
    while (payload.size() < h->payload_len) {
      const std::size_t have = payload.size();
      const std::size_t want = std::min(h->payload_len - have, kStep);
      payload.resize(have + want);
      read_exact(payload.data() + have, want);
    }
  } catch (const TransportError& e) {
    throw TransportError(e.kind(), std::string(e.what()) + " (block of '" + cmd + "' after " +
                                       "a partial read of " + std::to_string(h->payload_len) +
                                       " bytes expected)");
  }
  // Consume the message terminator that follows the block: "\n", or "\r\n"
  // (Red Pitaya's server ends every reply so).
  auto take = [&](std::uint8_t want) {
    if (!pending_.empty()) {
      if (pending_.front() != want) return false;
      pending_.erase(pending_.begin());
      return true;
    }
    if (pending_eom_) return false;
    // Byte stream: the terminator is still on its way; read it.
    std::uint8_t c = 0;
    bool eom = false;
    std::size_t n = read_some(&c, 1, &eom);
    if (n == 1 && c != want) pending_.insert(pending_.begin(), c);
    return n == 1 && c == want;
  };
  if (take('\r')) take('\n');
  else take('\n');
  return payload;
}

void ScpiClient::write_block(const std::string& prefix, std::span<const std::uint8_t> payload) {
  std::string h = prefix + block_header(payload.size());
  std::vector<std::uint8_t> msg(h.begin(), h.end());
  msg.insert(msg.end(), payload.begin(), payload.end());
  msg.push_back('\n');
  t_->send(msg);
}

void ScpiClient::check_errors(const std::string& context) {
  std::vector<std::string> errors;
  for (int i = 0; i < 32; ++i) {  // the queue is finite; 32 guards a babbling instrument
    std::string e = query("SYST:ERR?");
    int code = 0;
    auto [p, ec] = std::from_chars(e.data() + (e.starts_with("+") ? 1 : 0), e.data() + e.size(), code);
    if (ec != std::errc())
      throw InstrumentError(address_ + ": SYST:ERR? answered '" + e + "' (not an error entry)");
    if (code == 0) break;
    errors.push_back(e);
  }
  if (!errors.empty()) {
    std::string msg = address_ + ": instrument error after '" + context + "':";
    for (auto& e : errors) msg += " [" + e + "]";
    throw InstrumentError(msg);
  }
}

void ScpiClient::configure(const std::string& cmd) {
  write(cmd);
  std::string opc = query("*OPC?");
  if (opc != "1" && opc != "+1")
    throw InstrumentError(address_ + ": *OPC? after '" + cmd + "' answered '" + opc + "'");
  check_errors(cmd);
}

std::string ScpiClient::identify() {
  std::string idn = query("*IDN?");
  if (idn.empty()) throw InstrumentError(address_ + ": empty *IDN? reply");
  return idn;
}

}  // namespace piezo::drivers
