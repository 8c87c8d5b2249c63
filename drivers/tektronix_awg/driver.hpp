#pragma once
// Awg driver for Tektronix AWG5000 / AWG7000 generators over any Transport:
// the waveform goes to the waveform list as a REAL waveform, is assigned to
// channel 1 and played once per trigger (run mode TRIGgered); marker 1 of
// channel 1 triggers the DAQ. Every configuration step is followed by *OPC?
// and SYSTem:ERRor?; a failure names the step. Written from the programmer
// manual's command forms (see protocol.hpp); tested against the simulated
// twin (drivers/sim/sim_tektronix_awg.*) only, never against an instrument.
#include <functional>
#include <memory>
#include <string>

#include "drivers/awg.hpp"
#include "drivers/scpi_client.hpp"
#include "drivers/tektronix_awg/protocol.hpp"

namespace piezo::drivers::tektronix_awg {

class Driver : public Awg {
 public:
  // Connects: *IDN? must name a model of the table in protocol.hpp.
  explicit Driver(std::unique_ptr<Transport> t);
  // Whether an *IDN? reply names a supported model (for the driver registry).
  static bool supports(const std::string& idn) { return find_model(idn) != nullptr; }

  std::string identity() const override { return idn_; }
  const Model& model() const { return *model_; }
  void load(const ArbWaveform& w) override;
  void output(bool on) override;
  void trigger() override;

  // After AWGControl:RUN, how long to wait for "waiting for trigger" (the
  // instrument loads the waveform into its memory first).
  void set_run_timeout(double seconds) { run_timeout_s_ = seconds; }

 private:
  // Runs one step; an InstrumentError or TransportError is rethrown (same
  // type and kind) with the step's name in front.
  void step(const std::string& name, const std::function<void()>& f);
  void configure(const std::string& name, const std::string& cmd);
  bool waveform_exists(const std::string& name);
  int run_state();

  ScpiClient scpi_;
  std::string idn_;
  const Model* model_ = nullptr;
  double run_timeout_s_ = 10.0;
};

}  // namespace piezo::drivers::tektronix_awg
