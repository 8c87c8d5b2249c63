#include "ui/gui/residual_plot.hpp"

#include <cstdio>

#include "ui/gui/palette.hpp"

namespace piezo::gui {

namespace {
const char* short_kind(const std::string& kind) {
  if (kind == "frequency shift") return "shift";
  if (kind == "peak width/height") return "width";
  if (kind == "level") return "level";
  if (kind == "phase") return "phase";
  if (kind == "phase slope") return "slope";
  if (kind == "extra resonance") return "resonance";
  return "";
}

std::string region_detail(const update::GapRegion& g) {
  // A located region (update/residual_regions.hpp) in the verdict's words.
  if (!g.description.empty()) return g.name + ": " + g.description;
  char buf[200];
  int n = std::snprintf(buf, sizeof buf, "%s [%.1f-%.1f kHz]: %.0f %% of chi2, %s", g.name.c_str(),
                        g.f_lo_hz / 1e3, g.f_hi_hz / 1e3, 100 * g.share, g.kind.c_str());
  const auto more = [&](const char* f, double v) {
    if (n > 0 && static_cast<std::size_t>(n) < sizeof buf)
      n += std::snprintf(buf + n, sizeof buf - static_cast<std::size_t>(n), f, v);
  };
  if (g.kind == "frequency shift") more(" %+.3f %%", g.shift_pct);
  if (g.kind == "peak width/height") more(" (damping %+.1f %%)", g.width_pct);
  if (g.kind == "level") more(" %+.3f dB", g.level_db);
  if (g.kind == "phase") more(" %+.3f deg", g.phase_deg);
  return buf;
}

std::vector<double> khz(const std::vector<double>& f_hz) {
  std::vector<double> v;
  v.reserve(f_hz.size());
  for (double f : f_hz) v.push_back(f / 1e3);
  return v;
}

Series residual_series(const std::string& label, const update::GapCurve& c, bool phase,
                       ImU32 colour, double width) {
  return {label, khz(c.f_hz), phase ? c.residual_deg : c.residual_db, colour_of(colour), width};
}
}  // namespace

PlotSpec residual_plot_spec(const update::GapDiagnosis& d, bool phase) {
  PlotSpec spec{.title = phase ? "gap: residual phase" : "gap: residual |Z|",
                .x_label = "f [kHz]",
                .y_label = phase ? "deg" : "dB"};
  for (const auto& g : d.regions) {
    if (g.points == 0) continue;
    spec.bands.push_back({g.f_lo_hz / 1e3, g.f_hi_hz / 1e3, colour_of(region_colour(g.kind)),
                          short_kind(g.kind), "", region_detail(g)});
  }
  // Fitted to the bulk of the residual (issue 41 item 5): the 1st to 99th
  // percentile of the samples, so the band's edges do not stretch the axis
  // to +-40 dB over data within +-5 dB; a double-click shows every sample.
  spec.fit_y_quantile = 0.01;
  // The noise first and thin, the residuals on top.
  const auto& sig = phase ? d.before.sigma_deg : d.before.sigma_db;
  Series hi{"+/-2 sigma (noise)", khz(d.before.f_hz), {}, colour_of(kColNoiseBand), 1.0}, lo = hi;
  lo.listed = false;
  for (double v : sig) {
    hi.y.push_back(2 * v);
    lo.y.push_back(-2 * v);
  }
  spec.series.push_back(std::move(hi));
  spec.series.push_back(std::move(lo));
  spec.series.push_back(
      residual_series("updated model (base refit)", d.before, phase, kColResidual, 2.0));
  if (!d.added.empty()) {
    std::string label = "with";
    for (const auto& e : d.added) label += " " + e;
    spec.series.push_back(residual_series(label, d.after, phase, kColResidualAfter, 2.0));
  }
  return spec;
}

}  // namespace piezo::gui
