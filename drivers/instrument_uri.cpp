#include "drivers/instrument_uri.hpp"

#include <charconv>
#include <cstdio>
#include <stdexcept>

namespace piezo::drivers {

namespace {
[[noreturn]] void bad(std::string_view text, const std::string& why) {
  throw std::invalid_argument("instrument address '" + std::string(text) + "': " + why);
}

std::uint16_t parse_u16(std::string_view text, std::string_view s, int base, const char* what) {
  unsigned v = 0;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v, base);
  if (s.empty() || ec != std::errc() || p != s.data() + s.size() || v > 0xFFFF)
    bad(text, std::string("invalid ") + what + " '" + std::string(s) + "'");
  return static_cast<std::uint16_t>(v);
}
}  // namespace

InstrumentUri parse_instrument_uri(std::string_view text) {
  InstrumentUri u;
  if (text == "sim") return u;
  if (text.starts_with("sim?")) {
    const std::string_view q = text.substr(4);
    if (q == "awg=keysight" || q == "awg=tektronix") {
      u.sim_awg = std::string(q.substr(4));
      return u;
    }
    bad(text, "the simulated bench takes awg=keysight or awg=tektronix");
  }
  if (text.starts_with("tcp://")) {
    u.kind = InstrumentUri::Kind::Tcp;
    std::string_view rest = text.substr(6);
    auto colon = rest.rfind(':');
    if (colon == std::string_view::npos) bad(text, "expected tcp://HOST:PORT");
    u.host = std::string(rest.substr(0, colon));
    if (u.host.empty()) bad(text, "empty host");
    u.port = parse_u16(text, rest.substr(colon + 1), 10, "port");
    if (u.port == 0) bad(text, "port must be 1..65535");
    return u;
  }
  if (text.starts_with("usbtmc://")) {
    u.kind = InstrumentUri::Kind::UsbTmc;
    std::string_view rest = text.substr(9);
    auto slash = rest.find('/');
    std::string_view ids = rest.substr(0, slash);
    if (slash != std::string_view::npos) {
      std::string_view serial = rest.substr(slash + 1);
      if (serial.empty()) bad(text, "empty serial after '/'");
      u.serial = std::string(serial);
    }
    auto colon = ids.find(':');
    if (colon == std::string_view::npos) bad(text, "expected usbtmc://VID:PID[/SERIAL]");
    auto strip0x = [](std::string_view s) {
      return (s.starts_with("0x") || s.starts_with("0X")) ? s.substr(2) : s;
    };
    u.vid = parse_u16(text, strip0x(ids.substr(0, colon)), 16, "vendor id");
    u.pid = parse_u16(text, strip0x(ids.substr(colon + 1)), 16, "product id");
    return u;
  }
  bad(text, "unknown scheme; use sim, tcp://HOST:PORT or usbtmc://VID:PID[/SERIAL]");
}

std::string InstrumentUri::to_string() const {
  switch (kind) {
    case Kind::Sim:
      return sim_awg == "keysight" ? "sim" : "sim?awg=" + sim_awg;
    case Kind::Tcp:
      return "tcp://" + host + ":" + std::to_string(port);
    case Kind::UsbTmc: {
      char buf[32];
      std::snprintf(buf, sizeof buf, "usbtmc://%04x:%04x", vid, pid);
      return std::string(buf) + (serial ? "/" + *serial : "");
    }
  }
  return {};
}

}  // namespace piezo::drivers
