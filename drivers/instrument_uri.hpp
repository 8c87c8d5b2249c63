#pragma once
// Instrument addresses as the CLI and GUI spell them:
//   sim                         the embedded simulated bench (Keysight AWG twin)
//   sim?awg=tektronix           the same bench with the Tektronix AWG5014C twin
//                               (awg=keysight is the default)
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
  std::string sim_awg = "keysight";   // Sim: the AWG twin's dialect (keysight | tektronix)

  std::string to_string() const;
};

// Throws std::invalid_argument with a message naming the address and the problem.
InstrumentUri parse_instrument_uri(std::string_view text);

// "sim" or "sim?...": the embedded simulated bench (not checked further).
inline bool is_sim_address(std::string_view text) {
  return text == "sim" || text.starts_with("sim?");
}

}  // namespace piezo::drivers
