#pragma once
// The jobs' room (jobs/measure/): the simulated bench as every front end asks
// for it — `measure` and `sim-instrument` (ui/cli/cmd_measure.cpp), the GUI's
// instrument panel and the demo (jobs/demo_job.cpp) — one parsed request with
// its defaults here, and the one function that makes it the acquisition's
// acq::SimSpec. The front ends fill the fields from their options; nothing
// else builds a SimSpec from options.
#include <cstdint>
#include <string>
#include <vector>

#include "acquisition/sim_setup.hpp"
#include "model/tube_geometry.hpp"

namespace piezo::jobs {

struct SimBenchRequest {
  std::vector<std::string> effects;  // NAME=VALUE, the bench effects the model lacks (model/effects.hpp)
  std::string disturbance;           // a real bench's slow disturbances (drivers/sim/disturbances.hpp's string)
  std::string material = "apc850";   // the simulated transducer's material preset
  bool isotropic = false;            // the seed's isotropic class
  std::string set;                   // material overrides, "YE11=6.66e10,d31=-210e-12"
  double noise = 0.0;                // white noise per channel, std(noise)/std(signal)
  double rayleigh_beta = 1e-7;       // s (seed ch. 5)
  std::uint64_t seed = 1;            // noise seed
  int adc_bits = 14;                 // the simulated DAQ's resolution
};

// The bench's spec for a tube of geometry `g` (the plan's declared one).
// Throws std::invalid_argument naming a bad effect or disturbance.
acq::SimSpec sim_spec(const SimBenchRequest& r, const model::TubeGeometry& g = {});

// The effect table's names (model/effects.hpp) for the front ends' help:
// "a, b, c", `per_line` to a line (0: one line).
std::string sim_effect_names(std::size_t per_line = 0);

// "series_resistance=15, channel_skew=1e-7" (the GUI's panel) as NAME=VALUE
// items, blanks around each dropped, empty items skipped.
std::vector<std::string> split_sim_effects(const std::string& text);

}  // namespace piezo::jobs
