// The jobs' room (jobs/measure/): the simulated bench's request (sim_bench.hpp).
#include "jobs/measure/sim_bench.hpp"

#include <sstream>

#include "drivers/sim/disturbances.hpp"
#include "model/effects.hpp"

namespace piezo::jobs {

acq::SimSpec sim_spec(const SimBenchRequest& r, const model::TubeGeometry& g) {
  acq::SimSpec s;
  s.material = r.material;
  s.isotropic = r.isotropic;
  s.set = r.set;
  s.geometry = g;
  s.damping.beta = r.rayleigh_beta;
  s.noise_rel = r.noise;
  s.seed = r.seed;
  s.adc_bits = r.adc_bits;
  for (const auto& e : r.effects) model::apply_effect_assignment(s.effects, e);
  s.disturbances = drivers::sim::parse_disturbances(r.disturbance);  // throws naming the bad key
  return s;
}

std::vector<std::string> split_sim_effects(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
    if (b == std::string::npos) continue;
    out.push_back(item.substr(b, e - b + 1));
  }
  return out;
}

std::string sim_effect_names(std::size_t per_line) { return model::effect_names(per_line); }

}  // namespace piezo::jobs
