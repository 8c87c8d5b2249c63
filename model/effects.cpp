#include "model/effects.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace piezo::model {

namespace {
using cd = std::complex<double>;
constexpr double kInf = std::numeric_limits<double>::infinity();

// The terms of the circuit and DAQ stages (EffectStage; model/bench_response.hpp).
// A series resistance at or below zero is none: the divider has no negative
// resistor (a fit's coordinate may step there; the term stays 0 and flat).
cd resistance(double r, double) { return {r > 0 ? r : 0.0, 0.0}; }
cd capacitance_admittance(double c, double omega) { return {0.0, omega * c}; }
cd conductance_of(double r, double) { return {1.0 / r, 0.0}; }
cd relative_factor(double rel, double) { return {1.0 + rel, 0.0}; }
cd late_sampling(double tau, double omega) { return std::exp(cd(0.0, -omega * tau)); }

const EffectInfo kCatalogue[] = {
    {.name = "series_resistance", .unit = "ohm", .lower = 0.0, .upper = 200.0,
     .field = &EffectSet::series_resistance_ohm,
     .meaning = "resistance of leads and contacts in series with the transducer", .typical = 10.0,
     .separated_by = "the short standard of the fixture calibration",
     .stage = EffectStage::series, .term = resistance},
    {.name = "parallel_capacitance", .unit = "F", .lower = 0.0, .upper = 2e-9,
     .field = &EffectSet::parallel_capacitance_f,
     .meaning = "fixture and cable capacitance across the transducer terminals", .typical = 100e-12,
     .separated_by = "the open standard of the fixture calibration",
     .stage = EffectStage::shunt, .term = capacitance_admittance},
    {.name = "daq_input_resistance", .unit = "ohm", .lower = 1e3, .upper = kInf,
     .field = &EffectSet::daq_input_resistance_ohm,
     .meaning = "input resistance of the DAQ channel on the transducer node", .typical = 1e6,
     .separated_by = "the open standard of the fixture calibration (its conductance), or the DAQ's stated input resistance",
     .stage = EffectStage::shunt, .coordinate = EffectCoordinate::conductance, .term = conductance_of},
    {.name = "dielectric_loss", .unit = "tan_delta", .lower = 0.0, .upper = 0.1,
     .field = &EffectSet::dielectric_loss, .meaning = "dielectric loss tangent of the ceramic",
     .typical = 0.01,
     .separated_by = "the capacitance and tan delta measured below the first resonance (an LCR meter at 1 kHz, or a stepped sine there)"},
    {.name = "channel_skew", .unit = "s", .lower = -1e-6, .upper = 1e-6,
     .field = &EffectSet::channel_skew_s,
     .meaning = "sampling delay of channel 2 (v2) relative to channel 1 (v1)", .typical = 100e-9,
     .separated_by = "the open standard of the fixture calibration (its transfer's delay)",
     .stage = EffectStage::channel2, .term = late_sampling},
    {.name = "channel_gain", .unit = "fraction", .lower = -0.2, .upper = 0.2,
     .field = &EffectSet::channel_gain, .meaning = "relative gain error of channel 2", .typical = 0.01,
     .separated_by = "the load standard of the fixture calibration",
     .stage = EffectStage::channel2, .term = relative_factor},
    {.name = "r1_tolerance", .unit = "fraction", .lower = -0.2, .upper = 0.2,
     .field = &EffectSet::r1_tolerance,
     .meaning = "deviation of the true series resistor from its nominal value", .typical = 0.01,
     .separated_by = "the load standard of the fixture calibration, or R1 measured with an ohmmeter",
     .stage = EffectStage::r1, .term = relative_factor},
    {.name = "mass_loading", .unit = "fraction", .lower = 0.0, .upper = 0.5,
     .field = &EffectSet::mass_loading,
     .meaning = "mass added at the tube's end faces, as a fraction of the tube's mass", .typical = 0.01,
     .separated_by = "the tube weighed and measured (the model's density and geometry), or the tube measured unmounted",
     .moves_modes = true,
     // tests/update/test_gap_validation, GAP_EFFECTS=mass_loading
     .note = "its magnitude trades against the elastic constants (a lighter mass on a stiffer "
             "material): named in 13 of 14 simulated tubes, the fraction read low (0.2-1.0 x the true one)"},
    {.name = "mechanical_damping", .unit = "damping_ratio", .lower = 0.0, .upper = 0.05,
     .field = &EffectSet::mechanical_damping,
     .meaning = "modal damping ratio added to every mode (mounting/structural loss, not of Rayleigh form)",
     .typical = 1e-3,
     .separated_by = "the tube measured unmounted or in another mount (the damping moves, the constants do not)"},
};
}  // namespace

std::string separation_advice(const std::vector<std::string>& names) {
  // Effects with the same advice are named together, in the catalogue's order.
  std::vector<std::pair<std::string_view, std::string>> groups;
  for (const auto& e : kCatalogue) {
    if (std::find(names.begin(), names.end(), e.name) == names.end() || e.separated_by.empty()) continue;
    auto it = std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == e.separated_by; });
    if (it == groups.end()) groups.emplace_back(e.separated_by, std::string(e.name));
    else it->second += ", " + std::string(e.name);
  }
  std::string out;
  for (const auto& [how, who] : groups) out += (out.empty() ? "measure " : "; ") + who + " with " + std::string(how);
  return out;
}

bool EffectSet::any() const {
  EffectSet neutral;
  for (const auto& e : kCatalogue)
    if (this->*e.field != neutral.*e.field) return true;
  return false;
}

std::span<const EffectInfo> effect_catalogue() { return kCatalogue; }

double effect_coordinate_unit(const EffectInfo& e) {
  return e.coordinate == EffectCoordinate::conductance ? 1.0 / e.typical : e.typical;
}

double effect_coordinate(const EffectInfo& e, double value) {
  if (e.coordinate == EffectCoordinate::conductance)
    return std::isfinite(value) ? (1.0 / value) / effect_coordinate_unit(e) : 0.0;
  return value / effect_coordinate_unit(e);
}

double effect_from_coordinate(const EffectInfo& e, double x) {
  const double v = x * effect_coordinate_unit(e);
  if (e.coordinate == EffectCoordinate::conductance) return v > 0 ? 1.0 / v : kInf;
  return v;
}

double effect_sigma_from_coordinate(const EffectInfo& e, double x, double sigma_x) {
  const double u = effect_coordinate_unit(e), sv = sigma_x * u;
  if (e.coordinate != EffectCoordinate::conductance) return sv;
  const double v = x * u;
  return v > 0 ? sv / (v * v) : std::numeric_limits<double>::quiet_NaN();
}

std::pair<double, double> effect_coordinate_bounds(const EffectInfo& e) {
  const double u = effect_coordinate_unit(e);
  if (e.coordinate == EffectCoordinate::conductance) return {0.0, (1.0 / e.lower) / u};
  return {e.lower / u, e.upper / u};
}

void add_effect_coordinate(const EffectInfo& e, EffectSet& set, double x) {
  const double u = effect_coordinate_unit(e);
  double& f = set.*(e.field);
  if (e.coordinate == EffectCoordinate::conductance) {
    const double g = (std::isfinite(f) ? 1.0 / f : 0.0) + u * x;
    f = g != 0 ? 1.0 / g : kInf;
  } else {
    f += u * x;
  }
}

bool effect_value_physical(const EffectInfo& e, double value) {
  if (e.coordinate == EffectCoordinate::conductance) return std::isfinite(value) && value > 0;
  return value >= e.lower && value <= e.upper;
}

std::string effect_names(std::size_t per_line) {
  std::string out;
  std::size_t i = 0;
  for (const auto& e : kCatalogue) {
    if (i > 0) out += per_line && i % per_line == 0 ? ",\n" : ", ";
    out += e.name;
    ++i;
  }
  return out;
}

const EffectInfo* find_effect(std::string_view name) {
  for (const auto& e : kCatalogue)
    if (e.name == name) return &e;
  return nullptr;
}

void apply_effect_assignment(EffectSet& set, std::string_view a) {
  auto eq = a.find('=');
  if (eq == std::string_view::npos)
    throw std::invalid_argument("effect '" + std::string(a) + "': expected NAME=VALUE");
  std::string name(a.substr(0, eq)), value(a.substr(eq + 1));
  const EffectInfo* e = find_effect(name);
  if (!e) {
    throw std::invalid_argument("effect '" + name + "': unknown (known: " + effect_names() + ")");
  }
  char* end = nullptr;
  double v = std::strtod(value.c_str(), &end);
  if (value.empty() || *end != '\0' || std::isnan(v))
    throw std::invalid_argument("effect '" + name + "': '" + value + "' is not a number");
  if (v < e->lower || v > e->upper)
    throw std::invalid_argument("effect '" + name + "': " + value + " " + std::string(e->unit) +
                                " is outside the physical bounds [" + std::to_string(e->lower) + ", " +
                                std::to_string(e->upper) + "]");
  set.*(e->field) = v;
}

}  // namespace piezo::model
