#pragma once
// `piezobench model bar`: the seed's Appendix A bar vibrators (model/bar_vibrator.hpp)
// for a material preset and a bar — the resonance / anti-resonance pairs, the
// couplings, the capacitances, and for free-free bars the coupling IEEE Std
// 176 reads back from the first pair (it must equal the material's).
#include <nlohmann/json.hpp>
#include <string>

namespace piezo::jobs {

struct BarRequest {
  std::string material = "apc850";  // a preset (model/material_presets.hpp); its density is used
  std::string mode = "31";           // 31 | 33
  std::string ends = "free-free";    // free-free | fixed-mass
  double length_m = 0.02, width_m = 0.005, thickness_m = 0.002;
  double end_mass_kg = 0.0;          // fixed-mass only
  double fmax_hz = 0.0;              // 0: four times c/(2L)
};

// Throws InputError (jobs/job_error.hpp) for an unknown material, mode or
// ends, a bad dimension, or constants the mode cannot use (k ≥ 1).
nlohmann::json run_bar(const BarRequest& request);

}  // namespace piezo::jobs
