// `piezobench model bar` (model_bar_job.hpp).
#include "jobs/model_bar_job.hpp"

#include <cmath>
#include <stdexcept>

#include "jobs/job_error.hpp"
#include "model/bar_vibrator.hpp"
#include "model/material_presets.hpp"

namespace piezo::jobs {

namespace {

constexpr double kPi = 3.14159265358979323846;

// IEEE Std 176's coupling from a free-free bar's first pair: 31,
// k²/(1 - k²) = (π/2)(fa/fr) tan[(π/2)(fa - fr)/fr]; 33, k² = (π/2)(fr/fa) tan[(π/2)(fa - fr)/fa].
double ieee176_k(model::BarMode mode, double fr, double fa) {
  if (mode == model::BarMode::m31) {
    const double x = kPi / 2 * fa / fr * std::tan(kPi / 2 * (fa - fr) / fr);
    return std::sqrt(x / (1 + x));
  }
  return std::sqrt(kPi / 2 * fr / fa * std::tan(kPi / 2 * (fa - fr) / fa));
}

}  // namespace

nlohmann::json run_bar(const BarRequest& a) {
  if (a.mode != "31" && a.mode != "33") throw InputError("--mode must be 31 or 33, got '" + a.mode + "'");
  if (a.ends != "free-free" && a.ends != "fixed-mass")
    throw InputError("--ends must be free-free or fixed-mass, got '" + a.ends + "'");
  auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (!positive(a.length_m) || !positive(a.width_m) || !positive(a.thickness_m))
    throw InputError("--length, --width and --thickness must be > 0 (metres)");
  if (!std::isfinite(a.end_mass_kg) || a.end_mass_kg < 0) throw InputError("--end-mass must be >= 0 (kg)");
  if (!std::isfinite(a.fmax_hz) || a.fmax_hz < 0) throw InputError("--fmax must be >= 0 (0: four times c/(2L))");
  const model::BarMode mode = a.mode == "33" ? model::BarMode::m33 : model::BarMode::m31;
  const model::BarEnds ends = a.ends == "free-free" ? model::BarEnds::free_free : model::BarEnds::fixed_mass;
  if (ends == model::BarEnds::free_free && a.end_mass_kg != 0.0)
    throw InputError("--end-mass is for --ends fixed-mass");
  const model::MaterialPreset* preset = nullptr;
  try {
    preset = &model::find_preset(a.material);
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  model::BarGeometry g;
  g.length_m = a.length_m;
  g.width_m = a.width_m;
  g.thickness_m = a.thickness_m;
  g.density_kg_m3 = preset->density_kg_m3;
  g.end_mass_kg = a.end_mass_kg;
  model::BarConstants bc;
  try {
    bc = model::bar_constants(preset->material, g, mode);
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  const double speed = 1.0 / std::sqrt(g.density_kg_m3 * bc.compliance);
  const double fmax = a.fmax_hz > 0 ? a.fmax_hz : 4.0 * speed / (2.0 * g.length_m);
  if (!(fmax <= 1e9)) throw InputError("--fmax must lie in (0, 1e9] Hz");
  const auto pairs = model::bar_resonances(preset->material, g, mode, ends, fmax);
  nlohmann::json j;
  j["appendix"] = "A";
  j["mode"] = model::to_string(mode);
  j["ends"] = model::to_string(ends);
  j["material"] = preset->name;
  j["geometry"] = {{"length_m", g.length_m},     {"width_m", g.width_m},         {"thickness_m", g.thickness_m},
                   {"density_kg_m3", g.density_kg_m3}, {"bar_mass_kg", g.mass_kg()}, {"end_mass_kg", g.end_mass_kg}};
  j["k_material"] = bc.k;
  j["wave_compliance_m2_n"] = bc.compliance;
  j["wave_compliance"] = mode == model::BarMode::m33 ? "sD33 = sE33 (1 - k33^2)" : "sE11";
  j["wave_speed_m_s"] = speed;
  j["c_free_f"] = bc.c_free;
  j["c_clamped_f"] = bc.c_clamped;
  j["fmax_hz"] = fmax;
  j["pairs"] = nlohmann::json::array();
  for (const auto& p : pairs)
    j["pairs"].push_back({{"resonance_hz", p.resonance_hz},
                          {"antiresonance_hz", p.antiresonance_hz > 0 ? nlohmann::json(p.antiresonance_hz) : nlohmann::json(nullptr)},
                          {"k_eff", p.k_eff}});
  if (ends == model::BarEnds::free_free && !pairs.empty() && pairs[0].antiresonance_hz > 0)
    j["ieee176_k"] = ieee176_k(mode, pairs[0].resonance_hz, pairs[0].antiresonance_hz);
  return j;
}

}  // namespace piezo::jobs
