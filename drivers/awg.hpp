#pragma once
// Role interface of an arbitrary waveform generator: one channel driving R1.
#include <string>
#include <vector>

namespace piezo::drivers {

struct ArbWaveform {
  std::vector<double> samples;  // normalised to [-1, 1]
  double sample_rate_hz = 0.0;
  double peak_v = 1.0;  // output = peak_v · samples (into a high-impedance load)
};

class Awg {
 public:
  virtual ~Awg() = default;
  virtual std::string identity() const = 0;  // *IDN?
  // Loads the waveform, sets rate and amplitude, single-burst on a bus trigger,
  // sync/trigger output on. Each step checked with *OPC? and SYST:ERR?.
  virtual void load(const ArbWaveform& w) = 0;
  virtual void output(bool on) = 0;
  virtual void trigger() = 0;  // software trigger (*TRG): one burst
};

}  // namespace piezo::drivers
