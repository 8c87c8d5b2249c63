#pragma once
// Builds the embedded simulated bench: a tube of a given material and
// geometry (the FE model, reduced to its electrical port), the divider with
// the catalogue's circuit effects, and a DAQ with its own imperfections.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "drivers/sim/sim_bench.hpp"
#include "model/effects.hpp"
#include "model/port_model.hpp"
#include "model/tube_geometry.hpp"

namespace piezo::acq {

struct SimSpec {
  std::string material = "apc850";
  bool isotropic = false;  // the seed's isotropic class (§6.4.3)
  std::string set;  // overrides "YE11=6.66e10,nu12=0.3333,d31=-210e-12,epsT33_rel=2294"
  model::TubeGeometry geometry;
  model::RayleighDamping damping{0.0, 1e-7};  // seed ch. 5: β = 1e-7 s
  model::EffectSet effects;
  double noise_rel = 0.0;  // std(noise)/std(clean), both channels (seed's definition)
  double noise_v = 0.0;  // absolute noise floor per channel, V rms
  int adc_bits = 14;
  std::uint64_t seed = 1;
  drivers::sim::FaultPlan faults;
  int modes = 24;  // short-circuit modes kept in the port model
};

// `nominal_r1_ohm` is the resistor the technician declares; the bench's true
// resistor is nominal·(1 + effects.r1_tolerance).
std::shared_ptr<drivers::sim::SimBench> make_sim_bench(const SimSpec& spec, double nominal_r1_ohm);

}  // namespace piezo::acq
