// The pipeline's room (jobs/pipeline): the result corrected for the effect
// the gap diagnosis named (issue 41 item 2). The diagnosis refits the
// constants WITH the effect it names and checks the shrink of the gap on data
// the fit never saw; those constants, with their sigma, are the result — the
// update's own (without the effect) stay beside them (ParamRow::uncorrected).
#include <cmath>
#include <string>

#include "jobs/pipeline/capture_mode_figures.hpp"
#include "jobs/pipeline/stages.hpp"
#include "jobs/text/uncertain_text.hpp"
#include "model/effects.hpp"
#include "model/material.hpp"
#include "update/output_error/corrected.hpp"

namespace piezo::jobs::detail {

namespace {

bool names_an_effect(const update::GapDiagnosis& d) {
  return !d.verdict_effect.empty() && model::find_effect(d.verdict_effect) != nullptr;
}

struct Corrected {
  double value[4], sigma[4];
  std::string status[4];
};

void apply_rows(const Corrected& c, PipelineResult& out) {
  for (auto& row : out.params) {
    const int i = row.name == "YE11" ? 0 : row.name == "nu12" ? 1 : row.name == "d31" ? 2 : 3;
    row.uncorrected = row.updated;
    row.uncorrected_sigma = row.sigma;
    row.uncorrected_status = row.status;
    row.updated = c.value[i];
    row.sigma = std::isfinite(c.sigma[i]) ? std::optional<double>(c.sigma[i]) : std::nullopt;
    row.status = c.status[i];
  }
}

CorrectedConstants label_of(const update::GapDiagnosis& d, const std::string& unit, double value, double sigma,
                            const std::string& source) {
  CorrectedConstants k;
  k.effect = d.verdict_effect;
  k.unit = unit;
  k.value = value;
  k.sigma = sigma;
  k.heldout_shrink = d.heldout_shrink;
  k.heldout_without_gap = d.heldout_without_gap;
  k.source = source;
  k.label = "corrected for " + k.effect + " = " + format_uncertain(value, sigma, unit);
  if (d.heldout_shrink)
    k.label += " (held-out gap shrinks by " + std::to_string(std::lround(100.0 * *d.heldout_shrink)) + " %" + ")";
  else if (d.heldout_without_gap)
    k.label += " (the held-out data show no gap, and none with it)";
  else
    k.label += " (not checked on held-out data)";
  if (!d.verdict_alternatives.empty()) {
    std::string alt;
    for (const auto& a : d.verdict_alternatives) alt += (alt.empty() ? "" : ", ") + a;
    k.label += "; this capture cannot tell it from " + alt + ", which would correct the constants otherwise";
  }
  return k;
}

}  // namespace

void correct_constants(const PipelineRequest& req, const acq::Capture& cap, const CaptureModel& cm,
                       const update::OeResult* r, PipelineResult& out) {
  if (!out.diagnosis || out.params.empty() || !names_an_effect(*out.diagnosis)) return;
  const update::GapDiagnosis& d = *out.diagnosis;
  const double limit = req.oe_options.identifiable_rel_sigma;
  Corrected c;
  if (d.method == "output-error") {
    if (!r) return;
    const auto k = update::corrected_result(*r, d.verdict_effect, limit);
    if (!k) return;
    for (int i = 0; i < 4; ++i) {
      c.value[i] = k->parameters[static_cast<std::size_t>(i)].value;
      c.sigma[i] = k->parameters[static_cast<std::size_t>(i)].sigma;
      c.status[i] = k->parameters[static_cast<std::size_t>(i)].status;
    }
    const update::OeEffect* e = nullptr;
    for (const auto& x : r->effects)
      if (x.name == d.verdict_effect) e = &x;
    out.corrected = label_of(d, e->unit, e->value, e->sigma, "output-error");
    // The per-mode figures of the corrected model (they were the uncorrected fit's).
    if (out.mode_figures && out.mode_figures->error.empty() && out.output_error && out.output_error->ok()) {
      auto mm = model_mode_figures(cap, cm, *k, &*out.mode_figures);
      if (mm.error.empty()) {
        mm.source += ", " + out.corrected->label;
        out.mode_figures = std::move(mm);
      }
    }
  } else {
    if (d.steps.empty()) return;
    // The fit with every added effect (steps: each in the model with the previous ones).
    const auto& last = d.steps.back();
    const auto& first = d.steps.front();
    const update::TubeParams& p = last.material;
    const double v[4] = {p.y_e11, p.nu12, p.d31, p.eps_t33 / model::kEps0};
    for (int i = 0; i < 4; ++i) {
      const double rel = last.material_rel_sigma[i];
      c.value[i] = v[i];
      c.sigma[i] = rel * std::abs(v[i]);
      c.status[i] = std::isfinite(rel) && rel <= limit ? "ok" : "not identifiable";
    }
    out.corrected = label_of(d, first.unit, first.value, first.sigma, "impedance");
    if (d.added.size() > 1) {
      std::string more;
      for (std::size_t i = 1; i < d.added.size(); ++i) more += (i == 1 ? "" : ", ") + d.added[i];
      out.corrected->label += "; then " + more;
    }
  }
  apply_rows(c, out);
}

}  // namespace piezo::jobs::detail
