// The gap diagnosis plot (see diagnosis_plot.hpp).
#include "jobs/report/diagnosis_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ranges>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "jobs/report/plot_axes.hpp"
#include "jobs/text/uncertain_text.hpp"

namespace piezo::jobs::report {

namespace {

using namespace diagnosis_palette;
constexpr Colour kZero{0, 0, 0, 120};

std::string fmt(const char* f, double a, double b = 0, double c = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, f, a, b, c);
  return buf;
}

// An axis end moved out to the next 1-2-5 value when that is within 25 % (a labelled end).
double snap_down(double v) {
  for (double t : log_ticks(v / 1.25, v, true) | std::views::reverse)
    if (t <= v) return t;
  return v;
}
double snap_up(double v) {
  for (double t : log_ticks(v, v * 1.25, true))
    if (t >= v) return t;
  return v;
}

// Model |Z| from the measured one and the residual 20·log10|Z_meas/Z_model|.
std::vector<double> model_abs(const update::GapCurve& c) {
  std::vector<double> z(c.f_hz.size(), NAN);
  for (std::size_t i = 0; i < z.size(); ++i)
    z[i] = c.measured_abs_ohm[i] * std::pow(10.0, -c.residual_db[i] / 20.0);
  return z;
}

void check_curve(const update::GapCurve& c, const char* which) {
  const std::size_t n = c.f_hz.size();
  if (n < 2 || c.residual_db.size() != n || c.sigma_db.size() != n ||
      c.measured_abs_ohm.size() != n)
    throw std::invalid_argument(
        std::string("the diagnosis plot: the diagnosis holds no complete '") + which +
        "' curve");
}

// The plot's text as it has always been, ASCII: "±" as "+/-", "µ" as "u", "σ" as "sigma", "—" as "-".
std::string ascii_text(const std::string& t) {
  static const std::pair<std::string_view, std::string_view> kMap[] = {
      {"±", "+/-"}, {"µ", "u"}, {"σ", "sigma"}, {"—", "-"}};
  std::string out;
  for (std::size_t i = 0; i < t.size();) {
    bool mapped = false;
    for (const auto& [from, to] : kMap)
      if (t.compare(i, from.size(), from) == 0) {
        out += to;
        i += from.size();
        mapped = true;
        break;
      }
    if (!mapped) out += t[i++];
  }
  return out;
}

std::string verdict_line(const update::GapDiagnosis& d) {
  std::string s;
  if (d.verdict_effect == "none") {
    s = "no gap: the updated model matches within the noise";
  } else if (!d.steps.empty()) {
    const auto& e = d.steps.front();
    // σ to two significant digits, the value to match; ASCII "+/-" (the plot's font is ASCII).
    s = e.name + " = " + ascii_text(format_si(e.value, e.sigma, e.unit));
    for (std::size_t i = 1; i < d.steps.size(); ++i) s += ", then " + d.steps[i].name;
    if (d.heldout_shrink) s += fmt("; held-out gap shrinks by %.0f %%", 100 * *d.heldout_shrink);
  } else {
    s = "unexplained by the candidate effects";
  }
  s += fmt("   |   misfit sqrt(chi2/dof) %.2f on the fit data", d.gap_fit);
  if (d.gap_heldout) s += fmt(", %.2f held out", *d.gap_heldout);
  return s;
}

// Where the diagnosis located an unexplained misfit (regions with their
// phrase, update/residual_regions.hpp), only those: the named regions of the
// impedance-domain diagnosis would overlap them. Shaded alternately in every
// panel; named in the |Z| panel only.
std::vector<Band> region_bands(const update::GapDiagnosis& d, double fmin, double fmax, bool named) {
  std::vector<Band> out;
  const bool located = std::any_of(d.regions.begin(), d.regions.end(),
                                   [](const update::GapRegion& g) { return !g.description.empty(); });
  for (const auto& g : d.regions) {
    if (located && g.description.empty()) continue;
    const double lo = std::max(g.f_lo_hz, fmin), hi = std::min(g.f_hi_hz, fmax);
    if (!(hi > lo)) continue;
    Band b{lo, hi, out.size() % 2 ? kRegionB : kRegionA};
    if (named) {
      // A located region: its phrase, the verdict's words; too long to stand
      // upright in a narrow band: the kind (and where). A region holding a
      // tenth of χ² or more, not noise, says so and of what kind.
      b.label = g.name;
      if (!g.description.empty()) {
        b.label = g.description;
        b.short_label = g.resonance ? fmt("extra resonance %.2f kHz", g.resonance->f_hz / 1e3) : g.kind;
      } else if (g.share >= 0.1 && g.kind != "noise") {
        b.label += fmt(": %.0f %% of chi2, ", 100 * g.share) + g.kind;
      }
    }
    out.push_back(std::move(b));
  }
  return out;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

// A panel on the plot's frequency axis.
Panel frequency_panel(const std::string& y_label, double fmin, double fmax, double weight) {
  Panel p;
  p.x_label = "frequency";
  p.x_unit = "Hz";
  p.y_label = y_label;
  p.x_scale = Scale::Log;
  p.x_range = std::pair(fmin, fmax);
  p.height_weight = weight;
  return p;
}

// |Z|: the model after as a wide halo, the model before dashed, the
// measurement on top; the legend bottom left, below the capacitive line (|Z|
// falls from the top left).
Panel magnitude_panel(const update::GapDiagnosis& d, const update::GapCurve& after, double fmin,
                      double fmax) {
  const auto& f = d.before.f_hz;
  const auto meas = d.before.measured_abs_ohm, z_before = model_abs(d.before), z_after = model_abs(after);
  double lo = INFINITY, hi = 0;
  for (const auto* v : {&meas, &z_before, &z_after})
    for (double z : *v)
      if (z > 0 && std::isfinite(z)) lo = std::min(lo, z), hi = std::max(hi, z);
  if (!(hi > lo)) throw std::invalid_argument("the diagnosis plot: no positive |Z| to plot");
  const double pad = std::pow(hi / lo, 0.05);
  Panel p = frequency_panel("|Z| (ohm)", fmin, fmax, 0.48);
  p.y_scale = Scale::Log;
  p.y_range = std::pair(lo / pad, hi * pad);
  p.legend = LegendPlace::BottomLeft;
  std::string added;
  for (const auto& a : d.added) added += (added.empty() ? "" : " + ") + a;
  p.series.push_back({added.empty() ? "model after: no effect added" : "model after: + " + added, f, z_after,
                      kAfter, 4.0});
  p.series.push_back({"model before: base refit (material + damping)", f, z_before, kBefore, 1.8, true});
  p.series.push_back({"measured (" + d.fit_description + ")", f, meas, kMeasured, 1.4});
  p.fills.push_back({"\u00b11 sigma of the measurement (residual panels)", {}, {}, {}, kSigma});  // legend only
  p.bands = region_bands(d, fmin, fmax, true);
  return p;
}

// A residual, before and after, over the ±1σ band of the measurement. The
// range is symmetric and set by the better-measured half of the points (σ at
// most its median): 1.15 × their largest |residual|, at least 3 median σ.
// Where |Z| is small the noise is large, and its spikes would otherwise
// flatten the systematic misfit the diagnosis is about; they are clipped at
// the frame (the σ band shows why), and a note says so.
Panel residual_panel(const update::GapDiagnosis& d, const std::vector<double>& before,
                     const std::vector<double>& after, const std::vector<double>& sigma,
                     const std::string& label, const char* unit, double fmin, double fmax) {
  const auto& f = d.before.f_hz;
  std::vector<double> sig;
  for (double s : sigma)
    if (std::isfinite(s)) sig.push_back(s);
  const double sig_med = quantile(sig, 0.5);
  double well = 0, all = 0;
  for (std::size_t i = 0; i < f.size(); ++i)
    for (double r : {before[i], after[i]}) {
      if (!std::isfinite(r)) continue;
      all = std::max(all, std::abs(r));
      if (sigma[i] <= sig_med) well = std::max(well, std::abs(r));
    }
  const double lim = std::max({1.15 * well, 3.0 * sig_med, 1e-3});
  Panel p = frequency_panel(label, fmin, fmax, 0.26);
  p.y_range = std::pair(-lim, lim);
  std::vector<double> dn(sigma.size());
  for (std::size_t i = 0; i < sigma.size(); ++i) dn[i] = -sigma[i];
  p.fills.push_back({"", f, dn, sigma, kSigma});
  p.hlines.push_back({0.0, kZero, false});
  p.series.push_back({"", f, before, kBefore, 1.5});
  p.series.push_back({"", f, after, kAfter, 1.8});
  if (all > lim) p.note = fmt("clipped at \u00b1%.3g ", lim) + unit;
  p.bands = region_bands(d, fmin, fmax, false);
  return p;
}

// The figure around the panels: title with the verdict, the subtitle, the verdict's numbers.
Figure frame(const DiagnosisPlotOptions& opt, const std::string& verdict, std::string note) {
  Figure fig;
  fig.title = opt.title + " - verdict: " + verdict;
  fig.subtitle = opt.subtitle;
  fig.note = std::move(note);
  fig.width = opt.width;
  fig.height = opt.height;
  fig.shared_x = true;
  return fig;
}
}  // namespace

DiagnosisPlotLayout diagnosis_plot_layout(int width, int height) {
  Figure fig = frame({width, height, "t", "s"}, "v", "n");
  for (double w : {0.48, 0.26, 0.26}) fig.panels.push_back(frequency_panel("", 1, 10, w));
  const auto l = layout_figure(fig);
  return {l.plots[0], l.plots[1], l.plots[2]};
}

Figure diagnosis_figure(const update::GapDiagnosis& d, const DiagnosisPlotOptions& opt) {
  check_curve(d.before, "before");
  const update::GapCurve& after = d.after.f_hz.size() == d.before.f_hz.size() ? d.after : d.before;
  check_curve(after, "after");
  const auto& f = d.before.f_hz;
  const auto [fmin_it, fmax_it] = std::minmax_element(f.begin(), f.end());
  const double fmin = snap_down(*fmin_it), fmax = snap_up(*fmax_it);
  if (!(fmin > 0) || !(fmax > fmin))
    throw std::invalid_argument("the diagnosis plot: no frequency band to plot");
  Figure fig = frame(opt, d.verdict_effect, verdict_line(d));
  fig.panels.push_back(magnitude_panel(d, after, fmin, fmax));
  fig.panels.push_back(residual_panel(d, d.before.residual_db, after.residual_db, d.before.sigma_db,
                                      "residual |Z| (dB)", "dB", fmin, fmax));
  fig.panels.push_back(residual_panel(d, d.before.residual_deg, after.residual_deg, d.before.sigma_deg,
                                      "residual phase (deg)", "deg", fmin, fmax));
  return fig;
}

void write_diagnosis_png(const update::GapDiagnosis& d, const DiagnosisPlotOptions& opt,
                         const std::filesystem::path& file) {
  write_png(diagnosis_figure(d, opt), file);
}

}  // namespace piezo::jobs::report
