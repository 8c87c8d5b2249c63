#pragma once
// Simulated Keysight 33522B: the 33500-series SCPI subset the keysight33500
// driver uses (see drivers/keysight33500/protocol.hpp), over the shared SimBench,
// plus one simulator-only command, SIMulation:DUT (swaps the device at the
// terminals for the calibration standards; see sim_awg.cpp).
#include <map>
#include <memory>

#include "drivers/sim/scpi_device.hpp"
#include "drivers/sim/sim_bench.hpp"

namespace piezo::drivers::sim {

class SimAwg : public ScpiDevice {
 public:
  explicit SimAwg(std::shared_ptr<SimBench> bench) : bench_(std::move(bench)) {}

 protected:
  std::string idn() const override { return "Keysight Technologies,33522B,SIM0033522,piezobench-sim"; }
  bool command(const scpi::Command& c, const scpi::ProgramMessage& msg, Reply& out) override;

 private:
  void sim_dut(const scpi::Command& c, Reply& out);  // caller holds the bench mutex

  std::shared_ptr<SimBench> bench_;
  std::map<std::string, std::vector<float>> volatile_;  // named arbs in volatile memory
  bool swapped_ = false;
};

}  // namespace piezo::drivers::sim
