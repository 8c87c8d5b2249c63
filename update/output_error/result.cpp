// The output-error model's names and coordinates (update/output_error.hpp):
// the damping models' names, parsing and one-line summary, and the
// catalogue's effects as a coordinate of the fit (effect_coordinate).
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "model/effects.hpp"
#include "update/output_error.hpp"

namespace piezo::update {

const char* damping_name(OeDamping d) {
  return d == OeDamping::complex_constants ? "complex constants" : "rayleigh";
}

std::string damping_summary(const OeResult& r) {
  char buf[160];
  if (r.damping_model == OeDamping::complex_constants)
    std::snprintf(buf, sizeof buf, "complex constants Qm %.4g +- %.2g (1/Qm on cE)", r.qm,
                  r.qm_sigma);
  else
    std::snprintf(buf, sizeof buf, "Rayleigh beta %.4g s", r.damping.beta);
  return buf;
}

std::optional<OeDamping> parse_damping(const std::string& s) {
  if (s == "rayleigh") return OeDamping::rayleigh;
  if (s == "complex" || s == "complex constants" || s == "complex_constants")
    return OeDamping::complex_constants;
  return std::nullopt;
}

std::optional<EffectCoordinate> effect_coordinate(const std::string& name) {
  EffectCoordinate c;
  if (name == "daq_input_resistance") {  // 1/R: x·1 µS
    c.typical = 1e-6;
    c.apply = [](model::EffectSet& fx, double x) {
      const double g =
          (std::isfinite(fx.daq_input_resistance_ohm) ? 1.0 / fx.daq_input_resistance_ohm : 0.0) + 1e-6 * x;
      fx.daq_input_resistance_ohm = g != 0 ? 1.0 / g : INFINITY;
    };
    c.value = [](double x) { return 1e-6 * x; };
    return c;
  }
  // Typical sizes: the unit of the coordinate (a lead of 10 Ω, a cable of
  // 100 pF, a hard PZT's loss, a 100 ns skew, 1 % gain or R1, 1 % end mass,
  // a damping ratio of 1e-3).
  static const std::pair<const char*, std::pair<double model::EffectSet::*, double>> table[] = {
      {"series_resistance", {&model::EffectSet::series_resistance_ohm, 10.0}},
      {"parallel_capacitance", {&model::EffectSet::parallel_capacitance_f, 100e-12}},
      {"dielectric_loss", {&model::EffectSet::dielectric_loss, 0.01}},
      {"channel_skew", {&model::EffectSet::channel_skew_s, 1e-7}},
      {"channel_gain", {&model::EffectSet::channel_gain, 0.01}},
      {"r1_tolerance", {&model::EffectSet::r1_tolerance, 0.01}},
      {"mass_loading", {&model::EffectSet::mass_loading, 0.01}},
      {"mechanical_damping", {&model::EffectSet::mechanical_damping, 1e-3}},
  };
  for (const auto& [n, fe] : table) {
    if (name != n) continue;
    const auto [field, typ] = fe;
    c.typical = typ;
    c.apply = [field, typ](model::EffectSet& fx, double x) { fx.*field += typ * x; };
    c.value = [typ](double x) { return typ * x; };
    return c;
  }
  return std::nullopt;
}

}  // namespace piezo::update
