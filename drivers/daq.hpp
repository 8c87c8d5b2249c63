#pragma once
// Role interface of a two-channel digitizer sampling v1 (channel 1) and v2 (channel 2).
#include <string>
#include <vector>

namespace piezo::drivers {

enum class Coupling { Dc1M, Dc50, Ac };

struct DaqConfig {
  double sample_rate_hz = 1e7;
  std::size_t record_length = 20000;
  std::size_t pretrigger_samples = 0;
  double range_v[2] = {2.0, 2.0};  // symmetric full scale per channel: ±range_v
  Coupling coupling = Coupling::Dc1M;
  bool external_trigger = true;  // trigger from the AWG's sync output (AUX in)
};

struct DaqRecord {
  std::vector<double> v1, v2;  // volts
  double sample_rate_hz = 0.0;
  std::size_t pretrigger_samples = 0;
  double range_v[2] = {0.0, 0.0};
};

class Daq {
 public:
  virtual ~Daq() = default;
  virtual std::string identity() const = 0;
  virtual void configure(const DaqConfig& c) = 0;
  virtual void arm() = 0;  // single acquisition, waits for the trigger
  // Waits until the armed acquisition completed (timeout in seconds), then reads both channels.
  virtual DaqRecord fetch(double timeout_s) = 0;
};

}  // namespace piezo::drivers
