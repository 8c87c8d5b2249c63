// The jobs' room (jobs/): the simulated bench's effects (see sim_effects.hpp).
#include "jobs/sim_effects.hpp"

#include <sstream>

namespace piezo::jobs {

model::EffectSet parse_sim_effects(const std::string& text) {
  model::EffectSet set;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
    if (b == std::string::npos) continue;
    model::apply_effect_assignment(set, item.substr(b, e - b + 1));
  }
  return set;
}

}  // namespace piezo::jobs
