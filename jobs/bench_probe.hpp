#pragma once
// "Connect": open the bench exactly as a measurement would (acq::open_bench:
// transport, *IDN?, the driver's supported-model check) and report who
// answered, without acquiring. The GUI's instrument panel runs it on a
// worker thread; failures are thrown (drivers::TransportError for no
// instrument, drivers::InstrumentError for a refusal, std::invalid_argument for
// a bad address) so that the caller can say what to do.
#include <string>

#include "acquisition/sim_setup.hpp"

namespace piezo::jobs {

struct BenchProbe {
  std::string awg_idn, daq_idn;
  std::string description;  // as the capture's set-up will record it
};

// `awg` is "sim", tcp://HOST:PORT or usbtmc://VID:PID[/SERIAL]; `daq` may be
// empty (tcp: PORT+1 on the same host). For "sim", `sim` and `r1_ohm` build
// the embedded bench.
BenchProbe probe_bench(const std::string& awg, const std::string& daq, const acq::SimSpec& sim,
                       double r1_ohm);

}  // namespace piezo::jobs
