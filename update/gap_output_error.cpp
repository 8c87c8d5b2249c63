#include "update/gap_output_error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace piezo::update {

GapDiagnosis gap_from_output_error(const OeResult& r, const std::string& fit_description) {
  GapDiagnosis d;
  d.method = "output-error";
  d.n_fit = r.residual_samples;
  d.dof_fit = std::max(1, r.residual_samples - static_cast<int>(r.parameters.size()));
  d.chi2_fit = r.chi2_per_dof * d.dof_fit;
  d.gap_fit = std::sqrt(r.chi2_per_dof);
  d.fit_description = fit_description + "; output-error residual, noise from " + r.noise_source;
  d.material_base = r.updated;
  d.damping_base = r.damping;
  // g = √max(0, χ²/N − 1): the excess over the noise.
  const double g_before = std::sqrt(std::max(0.0, r.chi2_per_dof - 1.0));
  const OeEffect* top = nullptr;
  for (const auto& e : r.effects) {
    EffectReport rep;
    rep.name = e.name;
    rep.unit = e.unit;
    rep.alias = e.alias;
    rep.alias_residual = e.alias_residual;
    rep.typical = e.typical;
    rep.bias_y_e11_pct = e.bias_pct[0];
    rep.bias_nu12_pct = e.bias_pct[1];
    rep.bias_d31_pct = e.bias_pct[2];
    rep.bias_eps_t33_pct = e.bias_pct[3];
    rep.fitted = e.converged && !e.alias;
    rep.value = e.value;
    rep.sigma = e.sigma;
    rep.chi2_after = e.chi2_per_dof * std::max(1, d.dof_fit - 1);
    rep.delta_chi2 = e.delta_chi2;
    rep.shrink_fit = g_before > 0 ? 1.0 - std::sqrt(std::max(0.0, e.chi2_per_dof - 1.0)) / g_before : 0.0;
    rep.significant = e.significant;
    rep.material = e.material;
    if (e.alias)
      rep.note = "the constants mimic it in this capture (alias): measure it (fixture calibration) to separate it";
    d.effects.push_back(rep);
    if (e.significant && (!top || e.delta_chi2 > top->delta_chi2)) top = &e;
  }
  d.gap = r.lack_of_fit || top;
  // Without held-out data the verdict must explain the capture: an effect
  // that lowers χ² but leaves a lack of fit is the closest name of the
  // catalogue, not the cause (issue 21: never a false name).
  const OeEffect* closest = nullptr;
  if (top && !top->explains) {
    closest = top;
    top = nullptr;
  }
  char buf[600];
  if (!d.gap) {
    d.verdict_effect = "none";
    std::snprintf(buf, sizeof buf,
                  "No gap: the updated model explains the capture within its noise (output-error chi2/dof %.2f, "
                  "band test 1e%.1f).",
                  r.chi2_per_dof, r.band_log10_p);
    d.verdict = buf;
  } else if (top) {
    d.verdict_effect = top->name;
    d.added = {top->name};
    for (const auto& rep : d.effects)
      if (rep.name == top->name) d.steps = {rep};
    std::string twins;
    for (const auto& e : r.effects)
      if (&e != top && e.significant &&
          top->delta_chi2 - e.delta_chi2 <= std::max(4.0, 0.01 * top->delta_chi2)) {
        twins += (twins.empty() ? "" : ", ") + e.name;
        d.verdict_alternatives.push_back(e.name);
        for (auto& rep : d.effects)
          if (rep.name == top->name) rep.indistinguishable_from.push_back(e.name);
      }
    if (!d.steps.empty()) d.steps.front().indistinguishable_from = d.verdict_alternatives;
    std::snprintf(buf, sizeof buf, "Gap explained by %s = %.4g +/- %.2g %s (chi2 drops by %.0f; chi2/dof %.2f -> %.2f%s).",
                  top->name.c_str(), top->value, top->sigma, top->unit.c_str(), top->delta_chi2, r.chi2_per_dof,
                  top->chi2_per_dof, top->explains ? ", no lack of fit left" : ", some misfit left");
    d.verdict = buf;
    if (!twins.empty()) d.verdict += " This capture cannot tell it from " + twins + " (same signature).";
    d.verdict += " Not checked on held-out data.";
  } else {
    d.verdict_effect = "unexplained";
    std::string near;
    if (closest) {
      char c[300];
      std::snprintf(c, sizeof c,
                    " The closest effect of the catalogue, %s = %.4g %s, lowers chi2 by %.0f but leaves chi2/dof %.2f "
                    "(limit %.2f): it is not the cause, or not alone.",
                    closest->name.c_str(), closest->value, closest->unit.c_str(), closest->delta_chi2,
                    closest->chi2_per_dof, r.chi2_limit);
      near = c;
    }
    if (r.chi2_per_dof > r.chi2_limit)
      std::snprintf(buf, sizeof buf,
                    "Unexplained gap (output-error chi2/dof %.2f, limit %.2f): no effect of the catalogue explains it.",
                    r.chi2_per_dof, r.chi2_limit);
    else
      std::snprintf(buf, sizeof buf,
                    "Unexplained gap in %.3g-%.3g kHz (residual %.3g times the noise there, chance 1e%.1f): no effect "
                    "of the catalogue explains it.",
                    r.band_lo_hz / 1e3, r.band_hi_hz / 1e3, r.band_excess, r.band_log10_p);
    d.verdict = buf + near;
  }
  std::vector<std::string> aliases;
  for (const auto& e : r.effects)
    if (e.alias) aliases.push_back(e.name);
  if (!aliases.empty()) {
    d.verdict += " Not separable from the constants by this capture (aliases): ";
    for (std::size_t i = 0; i < aliases.size(); ++i) d.verdict += (i ? ", " : "") + aliases[i];
    d.verdict += " - calibrate the fixture to measure them.";
  }
  d.seconds = r.seconds;
  return d;
}

}  // namespace piezo::update
