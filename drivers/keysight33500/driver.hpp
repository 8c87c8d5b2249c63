#pragma once
// Awg driver for Keysight 33500B / 33600A generators over any Transport.
#include <memory>

#include "drivers/awg.hpp"
#include "drivers/scpi_client.hpp"

namespace piezo::drivers::keysight33500 {

class Driver : public Awg {
 public:
  // Connects: *IDN? must name a supported model (the table in protocol.hpp).
  explicit Driver(std::unique_ptr<Transport> t);
  // Whether an *IDN? reply names a supported model (for the driver registry).
  static bool supports(const std::string& idn);
  std::string identity() const override { return idn_; }
  void load(const ArbWaveform& w) override;
  void output(bool on) override;
  void trigger() override;
  // The SCPI session, for commands outside the Awg role (the simulator's SIM:DUT).
  ScpiClient& scpi() { return scpi_; }

 private:
  ScpiClient scpi_;
  std::string idn_;
  double max_rate_ = 0;
  std::size_t max_points_ = 0;
};

}  // namespace piezo::drivers::keysight33500
