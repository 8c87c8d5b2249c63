#pragma once
// The catalogue of bench effects that the FE model of the bare tube leaves
// out. One list serves two sides: the simulated bench injects them (physics
// and DAQ imperfections) and the gap diagnosis fits them as model extensions.
// Values are physical (SI); zero/neutral means "absent".
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace piezo::model {

struct EffectSet {
  double series_resistance_ohm = 0.0;  // lead/contact resistance in series with the tube
  double parallel_capacitance_f = 0.0;  // fixture and cable capacitance across the terminals
  double daq_input_resistance_ohm = std::numeric_limits<double>::infinity();  // loads the v2 node
  double dielectric_loss = 0.0;  // tan δ of the ceramic (εT33 → εT33·(1 − j·tanδ))
  // Its law in frequency: false, εT33·(1 − j·tanδ) at every frequency (the FE
  // convention: ANSYS's loss tangent, the refsim corpus); true, the causal
  // constant-phase law of model/bench_response.hpp (ε' falling ≈ 1.5·tanδ per
  // decade, as the simulated bench realises it with a Debye network).
  bool dielectric_constant_phase = false;
  double channel_skew_s = 0.0;  // channel 2 samples later than channel 1
  double channel_gain = 0.0;  // relative gain error of channel 2
  double r1_tolerance = 0.0;  // true R1 = nominal·(1 + r1_tolerance)
  double mass_loading = 0.0;  // added mass at the end faces, fraction of the tube mass
  // Damping ratio ξ_m added to EVERY mode (c_k += 2 ξ_m ω_k): frequency-
  // independent like a hysteretic/mounting loss, which the two-parameter
  // Rayleigh model (ξ = α/2ω + βω/2) cannot reproduce across the modes. (An
  // extra stiffness-proportional β would be absorbed exactly by the fitted
  // Rayleigh β, so it could never be a gap.)
  double mechanical_damping = 0.0;

  bool any() const;
};

struct EffectInfo {
  std::string_view name;  // CLI / JSON name
  std::string_view unit;
  double lower, upper;  // physical bounds used by the diagnosis and the CLI check
  double EffectSet::*field;
  std::string_view meaning;
  // A typical bench magnitude, in `unit` (issue 42: one value for both
  // diagnosis paths): the unit of the effect's fit coordinate and the size
  // the alias sentence ("a typical … would read as …") and the
  // detectability refer to. daq_input_resistance: 1 MΩ, fitted as its
  // conductance (effect_coordinate_unit).
  double typical;
  // What measures it apart from the constants when the impedance alone cannot
  // (an alias): the advice of the diagnosis' alias sentence.
  std::string_view separated_by;
};

// The alias sentence's advice for these effects: "measure X with Y; Z with W".
std::string separation_advice(const std::vector<std::string>& names);

// The unit of the effect's fit coordinate (x = value / unit): `typical`, or
// for daq_input_resistance the conductance 1/typical (siemens).
double effect_coordinate_unit(const EffectInfo& e);

std::span<const EffectInfo> effect_catalogue();
const EffectInfo* find_effect(std::string_view name);

// "NAME=VALUE" → sets the field; throws std::invalid_argument naming the
// effect and the problem (unknown name, not a number, out of bounds).
void apply_effect_assignment(EffectSet& set, std::string_view assignment);

}  // namespace piezo::model
