#pragma once
// Driver for the Red Pitaya STEMlab 125-14 over any Transport (its SCPI
// server listens on TCP port 5000). One instrument, both bench roles: the
// Generator (Awg: fast output 1 drives R1) and the Digitizer (Daq: IN1 = v1,
// IN2 = v2, triggered by the generator, ACQ:TRig AWG_PE) share one Session,
// i.e. one connection, so `measure --instrument tcp://HOST:5000` needs no
// --daq. Every configuration step is followed by *OPC? and SYST:ERR?; a
// failure names the step. Written from Red Pitaya's SCPI documentation and
// server sources (see protocol.hpp); tested against the simulated twin
// (drivers/sim/sim_redpitaya.*) only, never against a board.
#include <functional>
#include <memory>
#include <string>

#include "drivers/awg.hpp"
#include "drivers/daq.hpp"
#include "drivers/redpitaya/protocol.hpp"
#include "drivers/scpi_client.hpp"

namespace piezo::drivers::redpitaya {

// The one connection both roles talk through.
class Session {
 public:
  // Connects: *IDN? must name a Red Pitaya SCPI server (protocol.hpp).
  explicit Session(std::unique_ptr<Transport> t);
  const std::string& identity() const { return idn_; }
  const Board& board() const { return kStemlab125_14; }
  ScpiClient& scpi() { return scpi_; }
  // Runs one step; an InstrumentError or TransportError is rethrown (same
  // type and kind) with "Red Pitaya, step '<name>': " in front.
  void step(const std::string& name, const std::function<void()>& f);
  // write + *OPC? + SYST:ERR?, as one named step.
  void configure(const std::string& name, const std::string& cmd);

 private:
  ScpiClient scpi_;
  std::string idn_;
};

class Generator : public Awg {
 public:
  explicit Generator(std::shared_ptr<Session> s) : s_(std::move(s)) {}
  std::string identity() const override { return s_->identity(); }
  // Up to 16384 points, zero-padded to the 16384-point buffer (the idle
  // level after the burst), played once per trigger at the waveform's own
  // rate: SOUR1:FREQ:FIX = rate / 16384, so one period is the buffer.
  void load(const ArbWaveform& w) override;
  void output(bool on) override;
  void trigger() override;  // SOUR1:TRig:INT

 private:
  std::shared_ptr<Session> s_;
  bool loaded_ = false;
};

class Digitizer : public Daq {
 public:
  explicit Digitizer(std::shared_ptr<Session> s) : s_(std::move(s)) {}
  std::string identity() const override { return s_->identity(); }
  // The rate is rounded up to one of 125 MS/s / {1, 8, 64, 1024, 8192, 65536}
  // (the record states the actual rate); the range picks LV (±1 V) or HV
  // (±20 V) per input; at most 16384 samples (the buffer). DC coupling at
  // 1 Mohm and the generator trigger only: anything else is refused.
  void configure(const DaqConfig& c) override;
  void arm() override;
  DaqRecord fetch(double timeout_s) override;
  const RateChoice& rate() const { return rate_; }

 private:
  std::vector<double> read_input(int input);

  std::shared_ptr<Session> s_;
  DaqConfig cfg_;
  RateChoice rate_{1, 125e6};
  const Gain* gain_[2] = {nullptr, nullptr};
  bool configured_ = false;
};

struct Roles {
  std::unique_ptr<Generator> awg;
  std::unique_ptr<Digitizer> daq;
};
// Connects once and returns both roles over that connection.
Roles open(std::unique_ptr<Transport> t);
inline bool supports(const std::string& idn) { return accepts_idn(idn); }

}  // namespace piezo::drivers::redpitaya
