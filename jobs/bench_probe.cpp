#include "jobs/bench_probe.hpp"

#include <optional>

#include "acquisition/bench.hpp"
#include "drivers/instrument_uri.hpp"

namespace piezo::jobs {

BenchProbe probe_bench(const std::string& awg, const std::string& daq, const acq::SimSpec& sim,
                       double r1_ohm) {
  std::shared_ptr<drivers::sim::SimBench> sim_bench;
  if (drivers::is_sim_address(awg)) sim_bench = acq::make_sim_bench(sim, r1_ohm);
  acq::Bench b = acq::open_bench({awg, daq.empty() ? std::nullopt : std::optional(daq)}, sim_bench);
  return {b.awg->identity(), b.daq->identity(), b.description};
}

}  // namespace piezo::jobs
