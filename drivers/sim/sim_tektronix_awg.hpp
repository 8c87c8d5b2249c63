#pragma once
// Simulated Tektronix AWG5014C: the AWG5000/7000 SCPI subset the tektronix_awg
// driver uses (drivers/tektronix_awg/protocol.hpp) over the same SimBench as
// the Keysight twin, so the same FE-driven physics answers either dialect
// (`piezobench sim-instrument --dialect tektronix`). What it models:
//  - a waveform list with a few predefined waveforms and user REAL waveforms
//    (NEW refuses an existing name, DELete a missing one; deleting the
//    assigned waveform stops the run and switches the output off);
//  - run mode TRIGgered and the run state (AWGControl:RSTate?);
//  - the levels as specified into 50 ohm: the bench's divider is high
//    impedance, so the generator's EMF (what the bench physics is fed) is
//    twice the amplitude and the offset;
//  - marker 1 as the DAQ's trigger: a trigger plays one burst, and the DAQ
//    fires only if marker 1 rises with the burst's first point (marker high
//    above low). A marker rising later would trigger the DAQ late, which the
//    bench does not model: then the DAQ does not fire at all.
// Channel 1 only is wired to the bench; other channel suffixes are refused.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "drivers/sim/scpi_device.hpp"
#include "drivers/sim/sim_bench.hpp"
#include "drivers/tektronix_awg/protocol.hpp"

namespace piezo::drivers::sim {

class SimTektronixAwg : public ScpiDevice {
 public:
  explicit SimTektronixAwg(std::shared_ptr<SimBench> bench);

 protected:
  std::string idn() const override {
    return "TEKTRONIX,AWG5014C,SIM0005014,SCPI:99.0 FW:piezobench-sim";
  }
  bool command(const scpi::Command& c, const scpi::ProgramMessage& msg, Reply& out) override;

 private:
  struct Waveform {
    std::vector<float> values;
    std::vector<std::uint8_t> markers;
    bool predefined = false;
  };
  struct State {
    std::string assigned;  // channel 1's waveform, "" = none
    bool triggered_mode = false;
    int run_state = 0;  // 0 stopped, 1 waiting for trigger, 2 running
    double sample_rate_hz = 1.2e9;
    double amplitude_vpp = 1.0;  // into 50 ohm
    double offset_v = 0.0;
    double marker_low_v = 0.0, marker_high_v = 1.0;
    bool output_on = false;
    bool external_trigger = false;
  };

  bool waveform_list(const scpi::Command& c, const scpi::ProgramMessage& msg, Reply& out);
  bool source(const scpi::Command& c, Reply& out);
  void reset();
  void trigger();  // caller holds the bench mutex

  std::shared_ptr<SimBench> bench_;
  const tektronix_awg::Model& model_;
  std::vector<std::string> order_;  // the list in WLISt:NAME? order
  std::map<std::string, Waveform> list_;
  State s_;
};

}  // namespace piezo::drivers::sim
