#include "model/effects.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace piezo::model {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
const EffectInfo kCatalogue[] = {
    {"series_resistance", "ohm", 0.0, 200.0, &EffectSet::series_resistance_ohm,
     "resistance of leads and contacts in series with the transducer", 10.0,
     "the short standard of the fixture calibration"},
    {"parallel_capacitance", "F", 0.0, 2e-9, &EffectSet::parallel_capacitance_f,
     "fixture and cable capacitance across the transducer terminals", 100e-12,
     "the open standard of the fixture calibration"},
    {"daq_input_resistance", "ohm", 1e3, kInf, &EffectSet::daq_input_resistance_ohm,
     "input resistance of the DAQ channel on the transducer node", 1e6,
     "the open standard of the fixture calibration (its conductance), or the DAQ's stated input resistance"},
    {"dielectric_loss", "tan_delta", 0.0, 0.1, &EffectSet::dielectric_loss,
     "dielectric loss tangent of the ceramic", 0.01,
     "the capacitance and tan delta measured below the first resonance (an LCR meter at 1 kHz, or a stepped sine there)"},
    {"channel_skew", "s", -1e-6, 1e-6, &EffectSet::channel_skew_s,
     "sampling delay of channel 2 (v2) relative to channel 1 (v1)", 100e-9,
     "the open standard of the fixture calibration (its transfer's delay)"},
    {"channel_gain", "fraction", -0.2, 0.2, &EffectSet::channel_gain,
     "relative gain error of channel 2", 0.01,
     "the load standard of the fixture calibration"},
    {"r1_tolerance", "fraction", -0.2, 0.2, &EffectSet::r1_tolerance,
     "deviation of the true series resistor from its nominal value", 0.01,
     "the load standard of the fixture calibration, or R1 measured with an ohmmeter"},
    {"mass_loading", "fraction", 0.0, 0.5, &EffectSet::mass_loading,
     "mass added at the tube's end faces, as a fraction of the tube's mass", 0.01,
     "the tube weighed and measured (the model's density and geometry), or the tube measured unmounted"},
    {"mechanical_damping", "damping_ratio", 0.0, 0.05, &EffectSet::mechanical_damping,
     "modal damping ratio added to every mode (mounting/structural loss, not of Rayleigh form)", 1e-3,
     "the tube measured unmounted or in another mount (the damping moves, the constants do not)"},
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
  return e.name == "daq_input_resistance" ? 1.0 / e.typical : e.typical;
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
    std::string known;
    for (const auto& c : kCatalogue) known += (known.empty() ? "" : ", ") + std::string(c.name);
    throw std::invalid_argument("effect '" + name + "': unknown (known: " + known + ")");
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
