#include "drivers/comedi/address.hpp"

#include <charconv>
#include <stdexcept>

namespace piezo::drivers::comedi {

namespace {
[[noreturn]] void bad(std::string_view text, const std::string& why) {
  throw std::invalid_argument("Comedi address '" + std::string(text) + "': " + why);
}

unsigned parse_unsigned(std::string_view text, std::string_view s, const char* what) {
  unsigned v = 0;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || p != s.data() + s.size() || v > 255)
    bad(text, std::string("invalid ") + what + " '" + std::string(s) + "'");
  return v;
}
}  // namespace

bool is_comedi_address(std::string_view text) {
  return text.starts_with("comedi://") || text.starts_with("comedi-sim://");
}

Address parse_address(std::string_view text) {
  Address a;
  std::string_view rest;
  if (text.starts_with("comedi://")) {
    rest = text.substr(9);
  } else if (text.starts_with("comedi-sim://")) {
    a.simulated = true;
    rest = text.substr(13);
  } else {
    bad(text, "expected comedi:///dev/comediN[?options] or comedi-sim:///dev/comediN[?options]");
  }
  const auto q = rest.find('?');
  const std::string_view path = rest.substr(0, q);
  if (!path.starts_with("/dev/comedi") || path.size() == 11)
    bad(text, "the device must be /dev/comediN (three slashes after 'comedi:')");
  parse_unsigned(text, path.substr(11), "device number");
  a.device = std::string(path);
  if (q == std::string_view::npos) return a;
  std::string_view query = rest.substr(q + 1);
  while (!query.empty()) {
    const auto amp = query.find('&');
    const std::string_view item = query.substr(0, amp);
    query = amp == std::string_view::npos ? std::string_view{} : query.substr(amp + 1);
    const auto eq = item.find('=');
    if (eq == std::string_view::npos)
      bad(text, "option '" + std::string(item) + "' needs a value (NAME=VALUE)");
    const std::string_view key = item.substr(0, eq), value = item.substr(eq + 1);
    if (key == "trigger") {
      if (value == "software") {
        a.external_trigger = false;
      } else if (value.starts_with("pfi")) {
        a.external_trigger = true;
        a.pfi = parse_unsigned(text, value.substr(3), "PFI line");
      } else {
        bad(text, "trigger must be pfiN or software, not '" + std::string(value) + "'");
      }
    } else if (key == "edge") {
      if (value != "rising" && value != "falling") bad(text, "edge must be rising or falling");
      a.falling = value == "falling";
    } else if (key == "aref") {
      if (value == "diff")
        a.aref = Aref::Diff;
      else if (value == "rse")
        a.aref = Aref::Ground;
      else if (value == "nrse")
        a.aref = Aref::Common;
      else
        bad(text, "aref must be diff, rse or nrse, not '" + std::string(value) + "'");
    } else if (key == "channels") {
      const auto comma = value.find(',');
      if (comma == std::string_view::npos) bad(text, "channels must be two channel numbers, C1,C2");
      a.channels[0] = parse_unsigned(text, value.substr(0, comma), "channel");
      a.channels[1] = parse_unsigned(text, value.substr(comma + 1), "channel");
      if (a.channels[0] == a.channels[1]) bad(text, "v1 and v2 need two different channels");
    } else if (key == "softcal") {
      if (!a.simulated)
        bad(text, "softcal is an option of the simulated board (comedi-sim://) only");
      if (value != "0" && value != "1") bad(text, "softcal must be 0 or 1");
      a.sim_softcal = value == "1";
    } else {
      bad(text,
          "unknown option '" + std::string(key) + "' (trigger, edge, aref, channels, softcal)");
    }
  }
  return a;
}

std::string Address::to_string() const {
  std::string s = (simulated ? "comedi-sim://" : "comedi://") + device + "?trigger=";
  s += external_trigger ? "pfi" + std::to_string(pfi) : std::string("software");
  if (external_trigger && falling) s += "&edge=falling";
  s += std::string("&aref=") + (aref == Aref::Diff     ? "diff"
                                : aref == Aref::Ground ? "rse"
                                                       : "nrse");
  s += "&channels=" + std::to_string(channels[0]) + "," + std::to_string(channels[1]);
  if (sim_softcal) s += "&softcal=1";
  return s;
}

}  // namespace piezo::drivers::comedi
