#include "drivers/sim/scpi_device.hpp"

namespace piezo::drivers::sim {

void ScpiDevice::append(Reply& r, const std::string& s) {
  r.bytes.insert(r.bytes.end(), s.begin(), s.end());
}

void ScpiDevice::push_error(int code, const std::string& text) {
  if (errors_.size() < 30) errors_.push_back(std::to_string(code) + ",\"" + text + "\"");
}

Reply ScpiDevice::handle(const scpi::ProgramMessage& msg) {
  Reply r;
  auto parts = msg.has_block ? std::vector<std::string>{msg.text} : scpi::split_commands(msg.text);
  for (const auto& text : parts) {
    auto c = scpi::parse_command(text);
    if (c.header == "*IDN" && c.query) {
      append(r, idn() + "\n");
    } else if (c.header == "*OPC" && c.query) {
      append(r, "1\n");
    } else if (c.header == "*CLS") {
      errors_.clear();
    } else if (c.header == "*WAI" && !c.query) {
      // IEEE 488.2's wait-to-continue: every simulated command completes before the next.
    } else if (scpi::match("SYSTem:ERRor[:NEXT]", c.header) && c.query) {
      if (errors_.empty()) {
        append(r, "+0,\"No error\"\n");
      } else {
        append(r, errors_.front() + "\n");
        errors_.pop_front();
      }
    } else if (!command(c, msg, r)) {
      push_error(-113, "Undefined header; " + text.substr(0, 40));
    }
    if (r.close_connection || r.swallow) break;
  }
  return r;
}

}  // namespace piezo::drivers::sim
