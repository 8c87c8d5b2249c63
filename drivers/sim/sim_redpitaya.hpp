#pragma once
// Simulated Red Pitaya STEMlab 125-14: one SCPI server that is both the
// generator and the two-input acquisition, over the same SimBench (FE-driven
// physics, seeded noise) as the other twins, so `piezobench sim-instrument
// --dialect redpitaya` serves one port and `measure --instrument
// tcp://HOST:PORT` runs the redpitaya driver end to end. What it models:
//  - the generator's 16384-point arbitrary buffer (SOUR1:TRAC:DATA:DATA as
//    comma-separated floats), played once per SOUR1:TRig:INT in burst mode
//    with one cycle, at (points sent) × SOUR1:FREQ:FIX points per second;
//    SOUR1:VOLT is the peak into a high-impedance load, so the bench's EMF
//    is 2 × SOUR1:VOLT peak to peak;
//  - the acquisition: ACQ:DEC (1, 8, 64, 1024, 8192, 65536), ACQ:SOURn:GAIN
//    LV|HV (±1 V | ±20 V full scale, 14-bit codes), ACQ:TRig:DLY (the
//    trigger at sample 8192 - delay of the 16384-sample buffer), ACQ:START
//    then ACQ:TRig AWG_PE (the only source wired: the generator's burst),
//    ACQ:TRig:STAT? WAIT|TD, ACQ:TRig:FILL?, and ACQ:SOURn:DATA? as a
//    big-endian float32 block in volts (BIN) or "{v,...}" text (ASCII);
//  - replies to its own queries end in "\r\n", as the real server's do.
// The bench must quantise with 14 bits (the board's ADC); it refuses others.
#include <memory>
#include <string>
#include <vector>

#include "drivers/sim/scpi_device.hpp"
#include "drivers/sim/sim_bench.hpp"

namespace piezo::drivers::sim {

class SimRedPitaya : public ScpiDevice {
 public:
  explicit SimRedPitaya(std::shared_ptr<SimBench> bench);

 protected:
  std::string idn() const override { return "REDPITAYA,INSTR2020,0,01-02"; }
  bool command(const scpi::Command& c, const scpi::ProgramMessage& msg, Reply& out) override;
  // The block reply of ACQ:SOURn:DATA? (for fault-injecting subclasses).
  void data_reply(int input, Reply& out);

 private:
  struct Gen {
    std::vector<float> arb;  // as sent
    bool arb_function = false;
    double freq_hz = 1000.0;
    double amplitude_v = 1.0;
    double offset_v = 0.0;
    bool burst = false;
    int cycles = 1;
    int repetitions = 1;
    bool output_on = false;
  };
  struct Acq {
    unsigned decimation = 1;
    long delay = 0;
    bool high_gain[2] = {false, false};  // HV
    bool binary = false;
    bool volts = true;
    bool started = false;
    bool armed = false;  // started and waiting for AWG_PE
  };
  bool generator(const scpi::Command& c, Reply& out);
  bool acquisition(const scpi::Command& c, Reply& out);
  void apply_acquisition_settings();  // caller holds the bench mutex
  void fire();                        // SOUR1:TRig:INT; caller holds the mutex

  std::shared_ptr<SimBench> bench_;
  Gen gen_;
  Acq acq_;
};

}  // namespace piezo::drivers::sim
