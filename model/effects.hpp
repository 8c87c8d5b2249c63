#pragma once
// The catalogue of bench effects that the FE model of the bare tube leaves
// out. One list serves two sides: the simulated bench injects them (physics
// and DAQ imperfections) and the gap diagnosis fits them as model extensions.
// Values are physical (SI); zero/neutral means "absent".
#include <complex>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
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

// Where the bench applies an effect: the stages of model/bench_response.hpp's
// chain, from the tube outwards. An effect at the circuit or the DAQ is
// applied by its `term` alone, by the model (bench_response) and, for
// channel2, by the simulated bench too; an effect inside the tube has code
// of its own in the FE model, the modal response and the simulator.
enum class EffectStage {
  tube,      // inside the transducer (FE model, modal damping, dielectric)
  series,    // term = Z(value, ω), in series with the terminals
  shunt,     // term = Y(value, ω), across the v2 node
  r1,        // term = a real factor on the series resistor R1
  channel2,  // term = a factor on channel 2's transfer (the DAQ)
};

// The form in which the diagnosis fits an effect: its value, or the inverse
// (a conductance for a shunt resistance: x = (1/value) / (1/typical), so
// "absent", an infinite resistance, sits at x = 0).
enum class EffectCoordinate { linear, conductance };

struct EffectInfo {
  std::string_view name;  // CLI / JSON name
  std::string_view unit;
  double lower, upper;  // physical bounds used by the diagnosis and the CLI check
  double EffectSet::*field;
  std::string_view meaning;
  // A typical bench magnitude, in `unit` (issue 42: one value for both
  // diagnosis paths): the unit of the effect's fit coordinate and the size
  // the alias sentence ("a typical … would read as …") and the
  // detectability refer to. A conductance coordinate's unit is 1/typical.
  double typical;
  // What measures it apart from the constants when the impedance alone cannot
  // (an alias): the advice of the diagnosis' alias sentence.
  std::string_view separated_by;
  EffectStage stage = EffectStage::tube;
  EffectCoordinate coordinate = EffectCoordinate::linear;
  // The stage's term at `value` and ω (see EffectStage); null for tube effects.
  std::complex<double> (*term)(double value, double omega) = nullptr;
  // The simulated bench has an element of its own for it (the divider's
  // state space, the DAQ's skew and gain, the FE model). A channel2 effect
  // without one is applied to channel 2's record as its `term`
  // (acquisition/channel2_response.hpp); an effect at another stage needs one.
  bool simulated_natively = true;
  // It changes the FE model itself (its modes move nonlinearly, each
  // evaluation is a modal solve): the diagnosis keeps its exact Jacobian and
  // also starts it at 2 and 4 typical sizes.
  bool moves_modes = false;
  // A sentence the impedance-path diagnosis adds to the effect's report ("" none).
  std::string_view note = {};
};

// The alias sentence's advice for these effects: "measure X with Y; Z with W".
std::string separation_advice(const std::vector<std::string>& names);

// The unit of the effect's fit coordinate (x = value / unit): `typical`, or
// for a conductance coordinate 1/typical (siemens).
double effect_coordinate_unit(const EffectInfo& e);
// Value ↔ coordinate (x in units of effect_coordinate_unit). A conductance
// coordinate's x ≤ 0 is an infinite resistance (absent).
double effect_coordinate(const EffectInfo& e, double value);
double effect_from_coordinate(const EffectInfo& e, double x);
// The value's σ from the coordinate's x and σ_x (conductance: σ_R = σ_G/G²;
// NaN where G ≤ 0).
double effect_sigma_from_coordinate(const EffectInfo& e, double x, double sigma_x);
// The coordinate's bounds from the physical ones (conductance: [0, G_max]).
std::pair<double, double> effect_coordinate_bounds(const EffectInfo& e);
// Moves the effect in `set` by x coordinate units from where it is (a
// conductance adds to the present 1/value).
void add_effect_coordinate(const EffectInfo& e, EffectSet& set, double x);
// A fitted value inside the physical range (a conductance: a finite positive
// resistance).
bool effect_value_physical(const EffectInfo& e, double value);
// "name, name, ..." of the catalogue, `per_line` names to a line (0: one line).
std::string effect_names(std::size_t per_line = 0);

std::span<const EffectInfo> effect_catalogue();
const EffectInfo* find_effect(std::string_view name);

// "NAME=VALUE" → sets the field; throws std::invalid_argument naming the
// effect and the problem (unknown name, not a number, out of bounds).
void apply_effect_assignment(EffectSet& set, std::string_view assignment);

}  // namespace piezo::model
