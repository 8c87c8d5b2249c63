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
  const model::EffectInfo* info = model::find_effect(name);
  if (!info) return std::nullopt;
  EffectCoordinate c;
  // x units of the effect table's coordinate (model/effects.hpp, one table for
  // both diagnosis paths).
  c.apply = [info](model::EffectSet& fx, double x) { model::add_effect_coordinate(*info, fx, x); };
  return c;
}

}  // namespace piezo::update
