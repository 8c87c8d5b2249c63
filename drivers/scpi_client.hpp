#pragma once
// SCPI over any Transport: commands, queries, IEEE 488.2 binary blocks, and the
// configuration discipline of the drivers: every configuration step is
// followed by *OPC? and SYST:ERR? (IEEE 488.2 / SCPI-99 error queue).
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "drivers/transport.hpp"

namespace piezo::drivers {

// The instrument reported an error (SYST:ERR?) or answered nonsense.
class InstrumentError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Runs f; an InstrumentError or TransportError from it is rethrown, of the same
// kind, with `prefix` before its message — the drivers name the configuration
// step that failed ("Tektronix AWG, step 'amplitude': …").
void with_step_prefix(const std::string& prefix, const std::function<void()>& f);

class ScpiClient {
 public:
  explicit ScpiClient(std::unique_ptr<Transport> t);

  const std::string& address() const { return address_; }
  Transport& transport() { return *t_; }

  void write(const std::string& cmd);  // adds "\n"
  std::string query(const std::string& cmd);  // one response line, terminator stripped
  double query_double(const std::string& cmd);
  // Sends `cmd` and reads a definite-length block; returns the payload.
  std::vector<std::uint8_t> query_block(const std::string& cmd);
  // Sends `cmd_prefix` + block(payload) + "\n".
  void write_block(const std::string& cmd_prefix, std::span<const std::uint8_t> payload);

  // Sends cmd, then *OPC? (waits for completion), then drains SYST:ERR?;
  // throws InstrumentError naming the command if the instrument reported an error.
  void configure(const std::string& cmd);
  // Drains the error queue; throws InstrumentError listing every error after `context`.
  void check_errors(const std::string& context);
  // *IDN? (throws if empty).
  std::string identify();

 private:
  std::size_t read_some(std::uint8_t* buf, std::size_t max, bool* eom);
  std::string read_line();
  void read_exact(std::uint8_t* buf, std::size_t n);

  std::unique_ptr<Transport> t_;
  std::string address_;
  std::vector<std::uint8_t> pending_;  // bytes received beyond the last consumed message
  bool pending_eom_ = false;
};

}  // namespace piezo::drivers
