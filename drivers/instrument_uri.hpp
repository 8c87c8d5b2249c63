#pragma once
// Instrument addresses as the CLI and GUI spell them:
//   sim                         the embedded simulated bench
//   tcp://HOST:PORT             raw SCPI socket (LXI, usually port 5025)
//   usbtmc://VID:PID[/SERIAL]   USBTMC (USB488) device, VID/PID in hex
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace piezo::drivers {

struct InstrumentUri {
  enum class Kind { Sim, Tcp, UsbTmc };
  Kind kind = Kind::Sim;
  std::string host;  // Tcp
  std::uint16_t port = 0;  // Tcp
  std::uint16_t vid = 0, pid = 0;  // UsbTmc
  std::optional<std::string> serial;  // UsbTmc

  std::string to_string() const;
};

// Throws std::invalid_argument with a message naming the address and the problem.
InstrumentUri parse_instrument_uri(std::string_view text);

}  // namespace piezo::drivers
