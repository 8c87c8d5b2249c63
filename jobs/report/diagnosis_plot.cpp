// The gap diagnosis plot (see diagnosis_plot.hpp).
#include "jobs/report/diagnosis_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ranges>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "jobs/report/svg_plot.hpp"
#include "jobs/text/uncertain_text.hpp"

namespace piezo::jobs::report {

namespace {

using namespace diagnosis_palette;
constexpr Rgba kInk{35, 35, 35, 255};
constexpr Rgba kMuted{95, 95, 95, 255};
constexpr Rgba kGrid{0, 0, 0, 38};
constexpr Rgba kMinorGrid{0, 0, 0, 16};
constexpr Rgba kZero{0, 0, 0, 120};
constexpr Rgba kHalo{255, 255, 255, 200};

// Data → pixels on one axis; log axes map log10 of the value.
struct Axis {
  double lo = 0, hi = 1, p0 = 0, p1 = 1;
  bool log = false;
  double operator()(double v) const {
    if (log) {
      if (!(v > 0)) return NAN;
      return p0 + (std::log10(v) - std::log10(lo)) / (std::log10(hi) - std::log10(lo)) * (p1 - p0);
    }
    return p0 + (v - lo) / (hi - lo) * (p1 - p0);
  }
};

std::string fmt(const char* f, double a, double b = 0, double c = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, f, a, b, c);
  return buf;
}

// Labelled ticks of a log axis: 1, 2, 5 × 10^k (decades only beyond 4 decades).
std::vector<double> log_labels(double lo, double hi) {
  std::vector<double> out;
  const bool fine = std::log10(hi / lo) <= 4.0;
  for (int e = static_cast<int>(std::floor(std::log10(lo)));
       e <= static_cast<int>(std::ceil(std::log10(hi))); ++e)
    for (double m : {1.0, 2.0, 5.0}) {
      const double t = m * std::pow(10.0, e);
      if ((m == 1.0 || fine) && t >= lo * (1 - 1e-9) && t <= hi * (1 + 1e-9)) out.push_back(t);
    }
  return out;
}

// An axis end moved out to the next 1-2-5 value when that is within 25 % (a labelled end).
double snap_down(double v) {
  for (double t : log_labels(v / 1.25, v) | std::views::reverse)
    if (t <= v) return t;
  return v;
}
double snap_up(double v) {
  for (double t : log_labels(v, v * 1.25))
    if (t >= v) return t;
  return v;
}

// Grid lines of a log axis: every integer multiple of each decade.
std::vector<double> log_minor(double lo, double hi) {
  std::vector<double> out;
  for (int e = static_cast<int>(std::floor(std::log10(lo)));
       e <= static_cast<int>(std::ceil(std::log10(hi))); ++e)
    for (int m = 1; m <= 9; ++m) {
      const double t = m * std::pow(10.0, e);
      if (t >= lo && t <= hi) out.push_back(t);
    }
  return out;
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

std::vector<Point> points(const std::vector<double>& x, const std::vector<double>& y,
                          const Axis& ax, const Axis& ay) {
  std::vector<Point> p(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) p[i] = {ax(x[i]), ay(y[i])};
  return p;
}

// The plot's font is ASCII: "±" as "+/-", "µ" as "u", "σ" as "sigma", "—" as "-".
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

// Text readable over curves: a white halo one pixel around the glyphs.
void halo_text(PngCanvas& cv, double x, double y, const std::string& s, Align al, bool vertical) {
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      if (dx || dy) cv.text(x + dx, y + dy, s, kHalo, FontSize::Normal, al, vertical);
  cv.text(x, y, s, kInk, FontSize::Normal, al, vertical);
}

// The plot's x axis and the panels sharing it.
struct Frame {
  PngCanvas& cv;
  DiagnosisPlotLayout L;
  double fmin, fmax;
  Axis x(const PixelRect& p) const { return {fmin, fmax, p.x0, p.x1, true}; }
  std::vector<PixelRect> panels() const { return {L.z, L.db, L.deg}; }
};

// Regions as [lo, hi) bands inside the axis, and their alternate shading in every panel.
struct Band {
  double lo, hi;
  const update::GapRegion* region;
};

// Where the diagnosis located an unexplained misfit (regions with their
// phrase, update/residual_regions.hpp), only those: the named regions of the
// impedance-domain diagnosis would overlap them.
std::vector<Band> bands_of(const update::GapDiagnosis& d, double fmin, double fmax) {
  std::vector<Band> out;
  const bool located = std::any_of(d.regions.begin(), d.regions.end(),
                                   [](const update::GapRegion& g) { return !g.description.empty(); });
  for (const auto& g : d.regions) {
    if (located && g.description.empty()) continue;
    const double lo = std::max(g.f_lo_hz, fmin), hi = std::min(g.f_hi_hz, fmax);
    if (hi > lo) out.push_back({lo, hi, &g});
  }
  return out;
}

void shade_regions(const Frame& F, const std::vector<Band>& bands) {
  for (std::size_t k = 0; k < bands.size(); ++k)
    for (const PixelRect& P : F.panels()) {
      const Axis ax = F.x(P);
      F.cv.fill_rect(ax(bands[k].lo), P.y0, ax(bands[k].hi), P.y1, k % 2 ? kRegionB : kRegionA);
    }
}

// Vertical grid in every panel; tick labels under the last one.
void frequency_grid(const Frame& F) {
  for (const PixelRect& P : F.panels()) {
    const Axis ax = F.x(P);
    for (double t : log_minor(F.fmin, F.fmax))
      F.cv.line({std::round(ax(t)) + 0.5, P.y0}, {std::round(ax(t)) + 0.5, P.y1}, kMinorGrid);
    for (double t : log_labels(F.fmin, F.fmax))
      F.cv.line({std::round(ax(t)) + 0.5, P.y0}, {std::round(ax(t)) + 0.5, P.y1}, kGrid);
  }
  const PixelRect& P = F.L.deg;
  const Axis ax = F.x(P);
  for (double t : log_labels(F.fmin, F.fmax)) {
    F.cv.line({std::round(ax(t)) + 0.5, P.y1}, {std::round(ax(t)) + 0.5, P.y1 + 4}, kMuted);
    F.cv.text(ax(t), P.y1 + 6, t >= 1e3 ? fmt("%g kHz", t / 1e3) : fmt("%g Hz", t), kInk,
              FontSize::Normal, Align::Centre);
  }
  F.cv.text((P.x0 + P.x1) / 2, P.y1 + 24, "frequency", kInk, FontSize::Normal, Align::Centre);
}

// `s` cut to `max_w` pixels, ending in "..." when cut (whole code points only).
std::string fit_width(const PngCanvas& cv, const std::string& s, double max_w) {
  if (cv.text_width(s) <= max_w) return s;
  std::string t = s;
  while (!t.empty() && cv.text_width(t + "...") > max_w) {
    t.pop_back();
    while (!t.empty() && (static_cast<unsigned char>(t.back()) & 0xC0) == 0x80)
      t.pop_back();                                                                // continuation
    if (!t.empty() && static_cast<unsigned char>(t.back()) >= 0xC0) t.pop_back();  // lead byte
  }
  return t + "...";
}

// The frame of a panel and its y label: `label`, or `short_label` when the panel is too short for
// it.
void frame_and_label(const Frame& F, const PixelRect& P, const std::string& label,
                     const std::string& short_label) {
  F.cv.line({P.x0 - 0.5, P.y0 - 0.5}, {P.x1 + 0.5, P.y0 - 0.5}, kMuted);
  F.cv.line({P.x0 - 0.5, P.y1 + 0.5}, {P.x1 + 0.5, P.y1 + 0.5}, kMuted);
  F.cv.line({P.x0 - 0.5, P.y0 - 0.5}, {P.x0 - 0.5, P.y1 + 0.5}, kMuted);
  F.cv.line({P.x1 + 0.5, P.y0 - 0.5}, {P.x1 + 0.5, P.y1 + 0.5}, kMuted);
  const std::string& l = F.cv.text_width(label) + 8 <= P.y1 - P.y0 ? label : short_label;
  F.cv.text(14, (P.y0 + P.y1) / 2, l, kInk, FontSize::Normal, Align::Centre, true);
}

// |Z|: the model after as a wide halo, the model before dashed, the measurement on top.
void magnitude_panel(const Frame& F, const std::vector<double>& f, const std::vector<double>& meas,
                     const std::vector<double>& z_before, const std::vector<double>& z_after) {
  const PixelRect& P = F.L.z;
  double lo = INFINITY, hi = 0;
  for (const auto* v : {&meas, &z_before, &z_after})
    for (double z : *v)
      if (z > 0 && std::isfinite(z)) lo = std::min(lo, z), hi = std::max(hi, z);
  if (!(hi > lo)) throw std::invalid_argument("the diagnosis plot: no positive |Z| to plot");
  const double pad = std::pow(hi / lo, 0.05);
  const Axis ax = F.x(P), ay{lo / pad, hi * pad, P.y1, P.y0, true};
  for (double t : log_minor(ay.lo, ay.hi))
    F.cv.line({P.x0, std::round(ay(t)) + 0.5}, {P.x1, std::round(ay(t)) + 0.5}, kMinorGrid);
  for (double t : log_labels(ay.lo, ay.hi)) {
    const double y = std::round(ay(t)) + 0.5;
    F.cv.line({P.x0, y}, {P.x1, y}, kGrid);
    F.cv.line({P.x0 - 4, y}, {P.x0, y}, kMuted);
    F.cv.text(P.x0 - 7, y - 6, tick_label(t, Scale::Log), kInk, FontSize::Normal, Align::Right);
  }
  F.cv.set_clip(P.x0, P.y0, P.x1, P.y1);
  F.cv.polyline(points(f, z_after, ax, ay), kAfter, 4.0);
  F.cv.polyline(points(f, z_before, ax, ay), kBefore, 1.8, 7.0);
  F.cv.polyline(points(f, meas, ax, ay), kMeasured, 1.4);
  F.cv.reset_clip();
  frame_and_label(F, P, "|Z| (ohm)", "|Z|");
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

// A residual, before and after, over the ±1σ band of the measurement. The
// range is symmetric and set by the better-measured half of the points (σ at
// most its median): 1.15 × their largest |residual|, at least 3 median σ.
// Where |Z| is small the noise is large, and its spikes would otherwise
// flatten the systematic misfit the diagnosis is about; they are clipped at
// the frame (the σ band shows why), and a note says so.
void residual_panel(const Frame& F, const PixelRect& P, const std::vector<double>& f,
                    const std::vector<double>& before, const std::vector<double>& after,
                    const std::vector<double>& sigma, const std::string& label,
                    const std::string& short_label, const char* unit) {
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
  const bool clipped = all > lim;
  const Axis ax = F.x(P), ay{-lim, lim, P.y1, P.y0, false};
  for (double t : linear_ticks(-lim, lim, 5)) {
    const double y = std::round(ay(t)) + 0.5;
    F.cv.line({P.x0, y}, {P.x1, y}, t == 0.0 ? kZero : kGrid);
    F.cv.line({P.x0 - 4, y}, {P.x0, y}, kMuted);
    F.cv.text(P.x0 - 7, y - 6, tick_label(t, Scale::Linear), kInk, FontSize::Normal, Align::Right);
  }
  F.cv.set_clip(P.x0, P.y0, P.x1, P.y1);
  std::vector<double> px(f.size()), up(f.size()), dn(f.size());
  for (std::size_t i = 0; i < f.size(); ++i) {
    px[i] = ax(f[i]);
    up[i] = ay(sigma[i]);
    dn[i] = ay(-sigma[i]);
  }
  F.cv.fill_band(px, up, dn, kSigma);
  F.cv.polyline(points(f, before, ax, ay), kBefore, 1.5);
  F.cv.polyline(points(f, after, ax, ay), kAfter, 1.8);
  F.cv.reset_clip();
  if (clipped)
    halo_text(F.cv, P.x1 - 6, P.y0 + 4, fmt("clipped at \u00b1%.3g ", lim) + unit, Align::Right,
              false);
  frame_and_label(F, P, label, short_label);
}

// Region names at the top of the |Z| panel, on a white halo (they may cross a
// curve): horizontal in a band wide enough, else vertical, in frequency order
// at least a line apart (nudged off narrow neighbouring bands, never dropped).
// A region holding a tenth of χ² or more, not noise, says so and of what kind.
void region_names(const Frame& F, const std::vector<Band>& bands) {
  const PixelRect& P = F.L.z;
  const Axis ax = F.x(P);
  const double lh = F.cv.line_height();
  std::vector<double> xs(bands.size());
  std::vector<bool> flat(bands.size());
  std::vector<std::string> names(bands.size());
  for (std::size_t k = 0; k < bands.size(); ++k) {
    const auto& g = *bands[k].region;
    names[k] = g.name;
    if (!g.description.empty())  // a located region: its phrase, the verdict's words
      names[k] = g.description;
    else if (g.share >= 0.1 && g.kind != "noise")
      names[k] += fmt(": %.0f %% of chi2, ", 100 * g.share) + g.kind;
    const double xa = ax(bands[k].lo), xz = ax(bands[k].hi);
    flat[k] = xz - xa > F.cv.text_width(names[k]) + 12;
    if (!flat[k] && !g.description.empty())  // too long to stand in a narrow band: the kind (and where)
      names[k] = g.resonance ? fmt("extra resonance %.2f kHz", g.resonance->f_hz / 1e3) : g.kind;
    xs[k] = flat[k] ? (xa + xz) / 2 : std::round((xa + xz) / 2 - lh / 2);
  }
  for (std::size_t k = 1; k < xs.size(); ++k)  // left to right: keep a line apart
    if (!flat[k] && !flat[k - 1]) xs[k] = std::max(xs[k], xs[k - 1] + lh + 1);
  for (std::size_t k = xs.size(); k-- > 0;) {  // right to left: stay inside the panel
    if (flat[k]) continue;
    xs[k] = std::min(xs[k], P.x1 - lh - 2);
    if (k + 1 < xs.size() && !flat[k + 1]) xs[k] = std::min(xs[k], xs[k + 1] - lh - 1);
  }
  F.cv.set_clip(P.x0, P.y0, P.x1, P.y1);  // a long name on a short panel is cut, not spilled
  for (std::size_t k = 0; k < bands.size(); ++k) {
    const double y = flat[k] ? P.y0 + 6 : P.y0 + 6 + F.cv.text_width(names[k]);
    halo_text(F.cv, xs[k], y, names[k], flat[k] ? Align::Centre : Align::Left, !flat[k]);
  }
  F.cv.reset_clip();
}

// Bottom left of the |Z| panel, below the capacitive line (|Z| falls from the top left).
void legend(const Frame& F, const update::GapDiagnosis& d) {
  std::string added;
  for (const auto& a : d.added) added += (added.empty() ? "" : " + ") + a;
  const std::vector<std::pair<std::string, Rgba>> rows = {
      {"measured (" + d.fit_description + ")", kMeasured},
      {"model before: base refit (material + damping)", kBefore},
      {added.empty() ? "model after: no effect added" : "model after: + " + added, kAfter},
      {"\u00b11 sigma of the measurement (residual panels)", kSigma},
  };
  double w = 0;
  for (const auto& r : rows) w = std::max(w, F.cv.text_width(r.first));
  const double lh = F.cv.line_height() + 5, bw = w + 52,
               bh = static_cast<double>(rows.size()) * lh + 10;
  const double x0 = F.L.z.x0 + 8, y0 = F.L.z.y1 - bh - 8;
  F.cv.fill_rect(x0, y0, x0 + bw, y0 + bh, {255, 255, 255, 225});
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const double y = y0 + 6 + static_cast<double>(k) * lh, ym = std::round(y + lh / 2 - 3) + 0.5;
    if (k == 3)
      F.cv.fill_rect(x0 + 8, ym - 5, x0 + 38, ym + 5, rows[k].second);
    else if (k == 1)
      F.cv.polyline({{x0 + 8, ym}, {x0 + 38, ym}}, rows[k].second, 1.8, 7.0);
    else
      F.cv.line({x0 + 8, ym}, {x0 + 38, ym}, rows[k].second, k == 2 ? 4.0 : 1.6);
    F.cv.text(x0 + 46, y, rows[k].first, kInk);
  }
}

}  // namespace

DiagnosisPlotLayout diagnosis_plot_layout(int width, int height) {
  const double left = 84, right = width - 22.0, top = 92, bottom = height - 44.0, gap = 12;
  const double avail = bottom - top - 2 * gap, z_h = std::round(0.48 * avail),
               r_h = std::round((avail - z_h) / 2);
  DiagnosisPlotLayout l;
  l.z = {left, top, right, top + z_h};
  l.db = {left, l.z.y1 + gap, right, l.z.y1 + gap + r_h};
  l.deg = {left, l.db.y1 + gap, right, bottom};
  return l;
}

PngCanvas render_diagnosis_plot(const update::GapDiagnosis& d, const DiagnosisPlotOptions& opt) {
  check_curve(d.before, "before");
  const update::GapCurve& after = d.after.f_hz.size() == d.before.f_hz.size() ? d.after : d.before;
  check_curve(after, "after");
  const auto& f = d.before.f_hz;
  const auto [fmin_it, fmax_it] = std::minmax_element(f.begin(), f.end());
  const double fmin = snap_down(*fmin_it), fmax = snap_up(*fmax_it);
  if (!(fmin > 0) || !(fmax > fmin))
    throw std::invalid_argument("the diagnosis plot: no frequency band to plot");

  PngCanvas cv(opt.width, opt.height);
  const Frame F{cv, diagnosis_plot_layout(opt.width, opt.height), fmin, fmax};
  const auto bands = bands_of(d, fmin, fmax);
  shade_regions(F, bands);
  frequency_grid(F);
  magnitude_panel(F, f, d.before.measured_abs_ohm, model_abs(d.before), model_abs(after));
  residual_panel(F, F.L.db, f, d.before.residual_db, after.residual_db, d.before.sigma_db,
                 "residual |Z| (dB)", "resid. dB", "dB");
  residual_panel(F, F.L.deg, f, d.before.residual_deg, after.residual_deg, d.before.sigma_deg,
                 "residual phase (deg)", "resid. deg", "deg");
  region_names(F, bands);
  legend(F, d);

  // Title with the verdict (the normal size when the large one does not fit),
  // the subtitle, and the verdict's numbers.
  const std::string title = opt.title + " - verdict: " + d.verdict_effect;
  const FontSize ts =
      32 + cv.text_width(title, FontSize::Large) <= opt.width ? FontSize::Large : FontSize::Normal;
  double y = 10;
  cv.text(16, y, title, kInk, ts);
  y += cv.line_height(ts) + 6;
  if (!opt.subtitle.empty()) {
    cv.text(16, y, fit_width(cv, opt.subtitle, opt.width - 32), kInk);
    y += cv.line_height() + 3;
  }
  cv.text(16, y, fit_width(cv, verdict_line(d), opt.width - 32), kMuted);
  return cv;
}

void write_diagnosis_png(const update::GapDiagnosis& d, const DiagnosisPlotOptions& opt,
                         const std::filesystem::path& file) {
  render_diagnosis_plot(d, opt).save_png(file);
}

}  // namespace piezo::jobs::report
