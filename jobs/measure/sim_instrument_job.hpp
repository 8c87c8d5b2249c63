#pragma once
// The jobs' room (jobs/measure/): `piezobench sim-instrument` — the simulated
// bench served over TCP, so that the real transport and drivers run against
// it: the AWG on PORT (Keysight 33500 or Tektronix AWG5000 dialect) and the
// Infiniium DAQ on PORT+1, or one Red Pitaya STEMlab 125-14 (both roles) on
// PORT alone. ui/cli/cmd_measure.cpp parses the options and prints.
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

#include "jobs/measure/sim_bench.hpp"
#include "model/seed_circuit.hpp"

namespace piezo::jobs {

struct SimInstrumentRequest {
  std::string host = "127.0.0.1";
  int port = 5025;
  double r1 = model::kSeedR1Ohm;  // the bench's nominal series resistor
  double seconds = 0;             // 0: until cancelled
  std::string dialect = "keysight";  // keysight | tektronix | redpitaya
  SimBenchRequest sim;
};

// Where it listens, once it does.
struct SimInstrumentListening {
  bool one_instrument = false;  // redpitaya: both roles on awg_port (== daq_port)
  std::uint16_t awg_port = 0, daq_port = 0;
  std::string awg_name;  // "Keysight 33522B", "Tektronix AWG5014C", "Red Pitaya STEMlab 125-14"
};

struct SimInstrumentCallbacks {
  std::function<void(const std::string&)> note;  // something the user should know (not an error)
  std::function<void(const SimInstrumentListening&)> listening;
  const std::atomic<bool>* cancel = nullptr;  // stops serving when set
};

// Serves until `cancel` or `seconds`. Throws InputError for a bad port, a port
// in use or a host that is not an address (with the next step), and a bad
// option of the simulated bench.
void run_sim_instrument(const SimInstrumentRequest& req, const SimInstrumentCallbacks& cb);

}  // namespace piezo::jobs
