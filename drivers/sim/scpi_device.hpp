#pragma once
// Server side of a simulated SCPI instrument: takes complete program messages,
// returns the reply bytes. IEEE 488.2 common commands (*IDN?, *OPC?, *CLS,
// *RST) and the SCPI error queue (SYST:ERR?) are handled here; each
// instrument face implements the rest.
#include <deque>
#include <string>
#include <vector>

#include "drivers/scpi_parse.hpp"

namespace piezo::drivers::sim {

struct Reply {
  std::vector<std::uint8_t> bytes;
  bool close_connection = false;  // fault injection: drop the link after sending `bytes`
  bool swallow = false;  // fault injection: never answer (the client times out)
};

class ScpiDevice {
 public:
  virtual ~ScpiDevice() = default;
  Reply handle(const scpi::ProgramMessage& msg);

 protected:
  virtual std::string idn() const = 0;
  // Returns false for an unknown header (→ error -113). Appends to `out`.
  virtual bool command(const scpi::Command& c, const scpi::ProgramMessage& msg, Reply& out) = 0;
  void push_error(int code, const std::string& text);
  static void append(Reply& r, const std::string& s);

 private:
  std::deque<std::string> errors_;
};

}  // namespace piezo::drivers::sim
