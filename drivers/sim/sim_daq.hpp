#pragma once
// Simulated Keysight Infiniium DSO9104A: the SCPI subset the infiniium driver
// uses (see drivers/infiniium/protocol.hpp), over the shared SimBench.
#include <memory>

#include "drivers/sim/scpi_device.hpp"
#include "drivers/sim/sim_bench.hpp"

namespace piezo::drivers::sim {

class SimDaq : public ScpiDevice {
 public:
  explicit SimDaq(std::shared_ptr<SimBench> bench) : bench_(std::move(bench)) {}

 protected:
  std::string idn() const override { return "KEYSIGHT TECHNOLOGIES,DSO9104A,SIM0009104,piezobench-sim"; }
  bool command(const scpi::Command& c, const scpi::ProgramMessage& msg, Reply& out) override;

 private:
  void waveform_data(Reply& out);

  std::shared_ptr<SimBench> bench_;
  int source_ = 1;
  bool word_ = false;
  bool lsb_first_ = false;
  bool ader_ = false;  // acquisition-done event, cleared by reading :ADER?
};

}  // namespace piezo::drivers::sim
