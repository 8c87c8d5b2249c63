#pragma once
// Daq driver for Keysight Infiniium oscilloscopes over any Transport.
#include <memory>

#include "drivers/daq.hpp"
#include "drivers/scpi_client.hpp"

namespace piezo::drivers::infiniium {

class Driver : public Daq {
 public:
  explicit Driver(std::unique_ptr<Transport> t);
  // Whether an *IDN? reply names a supported model (for the driver registry).
  static bool supports(const std::string& idn);
  std::string identity() const override { return idn_; }
  void configure(const DaqConfig& c) override;
  void arm() override;
  DaqRecord fetch(double timeout_s) override;

 private:
  std::vector<double> read_channel(int ch);

  ScpiClient scpi_;
  std::string idn_;
  double max_rate_ = 0;
  std::size_t max_points_ = 0;
  DaqConfig cfg_;
  bool configured_ = false;
};

}  // namespace piezo::drivers::infiniium
