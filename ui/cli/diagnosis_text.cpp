#include "ui/cli/diagnosis_text.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "jobs/text/uncertain_text.hpp"
#include "model/effects.hpp"

namespace piezo::cli {

namespace {
std::string fmt(const char* f, double a, double b = 0, double c = 0) {
  char buf[128];
  std::snprintf(buf, sizeof buf, f, a, b, c);
  return buf;
}

std::string effect_unit(const std::string& name) {
  const model::EffectInfo* e = model::find_effect(name);
  return e ? std::string(e->unit) : std::string();
}
}  // namespace

void print_diagnosis(std::ostream& os, const update::GapDiagnosis& d) {
  os << "\n  gap diagnosis (" << d.fit_description;
  if (!d.heldout_description.empty()) os << "; " << d.heldout_description;
  os << ")\n";
  os << fmt("    misfit sqrt(chi2/dof) %.2f on the fit data", d.gap_fit);
  if (d.gap_heldout) os << fmt(", %.2f held out", *d.gap_heldout);
  os << " (1 = at the noise)\n";
  if (!d.regions.empty()) os << "    where (share of chi2, kind):\n";
  for (const auto& g : d.regions) {
    if (g.points == 0) continue;
    if (!g.description.empty()) {  // a located region (update/residual_regions.hpp): its phrase, as in the verdict
      os << fmt("      %5.1f %%  ", 100 * g.share) << g.name << ": " << g.description << "\n";
      continue;
    }
    os << fmt("      %5.1f %%  ", 100 * g.share) << g.name << fmt(" [%.1f-%.1f kHz]: ", g.f_lo_hz / 1e3, g.f_hi_hz / 1e3)
       << g.kind;
    if (g.kind == "frequency shift") os << fmt(" %+.3f %%", g.shift_pct);
    if (g.kind == "peak width/height") os << fmt(" damping %+.1f %%", g.width_pct);
    if (g.kind == "level") os << fmt(" %+.3f dB", g.level_db);
    if (g.kind == "phase") os << fmt(" %+.3f deg", g.phase_deg);
    os << "\n";
  }
  if (!d.measured.empty()) {
    os << "    measured (fixture calibration), held in the model:\n";
    for (const auto& m : d.measured)
      os << "      " << m.name << ": "
         << jobs::format_si(m.value, m.sigma > 0 ? m.sigma : NAN, effect_unit(m.name), {false, 6, "σ not known"})
         << "\n";
  }
  os << "    candidate effects (refitted with the constants; held-out shrink decides):\n";
  for (const auto& e : d.effects) {
    os << "      " << e.name << ": ";
    if (e.alias) {
      os << fmt("ALIAS (%.1f %% of its signature left; a typical %.3g ", 100 * e.alias_residual, e.typical) << e.unit
         << fmt(" would read as epsT33 %+.2f %%, d31 %+.2f %%", e.bias_eps_t33_pct, e.bias_d31_pct)
         << fmt(", YE11 %+.2f %%)", e.bias_y_e11_pct) << "\n";
      continue;
    }
    os << jobs::format_si(e.value, e.sigma, e.unit) << fmt(", delta chi2 %.1f", e.delta_chi2)
       << (e.significant ? " (significant)" : "");
    if (e.heldout_shrink) os << fmt(", held-out shrink %.0f %%", 100 * *e.heldout_shrink);
    os << "\n";
  }
  os << "    verdict: " << d.verdict << "\n";
}

void print_corrected(std::ostream& os, const jobs::PipelineResult& r) {
  if (!r.corrected) return;
  os << "\n  result: " << r.corrected->label << "\n";
  char line[256];
  std::snprintf(line, sizeof line, "  %-11s %-28s %-17s | %-28s %s\n", "parameter", "corrected ± sigma", "status",
                "without it ± sigma", "status");
  os << line;
  for (const auto& p : r.params) {
    const jobs::UncertainStyle compact{true};
    const std::string a = jobs::format_uncertain(p.updated, p.sigma.value_or(NAN), {}, compact);
    const std::string b = p.uncorrected
                              ? jobs::format_uncertain(*p.uncorrected, p.uncorrected_sigma.value_or(NAN), {}, compact)
                              : std::string("-");
    std::snprintf(line, sizeof line, "  %-11s %-28s %-17s | %-28s %s", p.name.c_str(), a.c_str(), p.status.c_str(),
                  b.c_str(), p.uncorrected_status.c_str());
    os << line;
    if (p.truth && p.sigma && *p.sigma > 0)  // the simulated bench's truth (demo only)
      os << "   (true " << jobs::format_value(*p.truth, {}, 6) << ": "
         << jobs::format_value((p.updated - *p.truth) / *p.sigma, {}, 2) << " sigma)";
    os << "\n";
  }
}

}  // namespace piezo::cli
