#pragma once
// Builds the embedded simulated bench: a tube of a given material and
// geometry (the FE model, reduced to its electrical port), the divider with
// the catalogue's circuit effects, a DAQ with its own imperfections, and
// optionally a real bench's slow disturbances (drivers/sim/disturbances.hpp).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "acquisition/parasitic_branch.hpp"
#include "drivers/sim/sim_bench.hpp"
#include "model/effects.hpp"
#include "model/port_model.hpp"
#include "model/tube_geometry.hpp"

namespace piezo::acq {

// Causes the effect catalogue (model/effects.hpp) does NOT describe, for
// validating that the gap diagnosis answers "unexplained" rather than a false
// name (issue 21). Simulator inputs only: they are kept out of
// model::EffectSet so the diagnosis cannot fit them. All default to absent, and
// an absent one changes nothing (not even the capture's /truth group).
struct UnmodelledEffects {
  // Series R-L-C branches across the tube's terminals (inside the series lead
  // resistance), each given by its series resonance f, coupling k_eff and Q
  // against the tube's static capacitance (acquisition/parasitic_branch.hpp).
  std::vector<ParasiticResonance> parasitic_branches;
  // Fluid loading the outer surface as a radial dashpot, Z_a = ρ_f·c_f in
  // Pa·s/m (water 1.48e6): per-mode damping from the FE shapes
  // (ModalOptions::outer_surface_impedance, model/outer_surface_damping.hpp);
  // none on the residual pseudo-mode.
  double acoustic_impedance_pa_s_m = 0.0;
  // Geometry error: the true tube's wall is (1 + rel) times the wall of
  // SimSpec::geometry, at the same inner diameter (outer diameter
  // Di + (Do − Di)(1 + rel)). SimSpec::geometry stays the DECLARED tube: the
  // measurement plan's Setup declares its own geometry independently (absent
  // fields = model::TubeGeometry's defaults, the same as SimSpec's default),
  // so a geometry-error case is SimSpec::geometry = the plan's declared
  // geometry and wall_thickness_rel = ±0.03. Must be > −1.
  double wall_thickness_rel = 0.0;
};

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
  UnmodelledEffects unmodelled;  // issue 21: causes outside the catalogue (simulator only)
  // Issue 33: offsets, mains hum, pink noise, drift and step of the tube's
  // constants, trigger jitter (parse_disturbances reads the option string).
  // All off by default, and off the bench is as it was, sample for sample.
  drivers::sim::Disturbances disturbances;
};

// The tube the simulated bench really has: SimSpec::geometry with the
// unmodelled wall-thickness error applied (density not yet set).
model::TubeGeometry true_geometry(const SimSpec& spec);

// `nominal_r1_ohm` is the resistor the technician declares; the bench's true
// resistor is nominal·(1 + effects.r1_tolerance).
std::shared_ptr<drivers::sim::SimBench> make_sim_bench(const SimSpec& spec, double nominal_r1_ohm);

}  // namespace piezo::acq
