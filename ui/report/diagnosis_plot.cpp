// The gap diagnosis plot (see diagnosis_plot.hpp).
#include "ui/report/diagnosis_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ranges>
#include <stdexcept>

#include "ui/report/svg_plot.hpp"

namespace piezo::report {

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
        std::string("render_diagnosis_plot: the diagnosis holds no complete '") + which +
        "' curve");
}

std::vector<Point> points(const std::vector<double>& x, const std::vector<double>& y,
                          const Axis& ax, const Axis& ay) {
  std::vector<Point> p(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) p[i] = {ax(x[i]), ay(y[i])};
  return p;
}

std::string verdict_line(const update::GapDiagnosis& d) {
  std::string s;
  if (d.verdict_effect == "none") {
    s = "no gap: the updated model matches within the noise";
  } else if (!d.steps.empty()) {
    const auto& e = d.steps.front();
    s = e.name + fmt(" = %.4g +/- %.2g ", e.value, e.sigma) + e.unit;
    for (std::size_t i = 1; i < d.steps.size(); ++i) s += ", then " + d.steps[i].name;
    if (d.heldout_shrink) s += fmt("; held-out gap shrinks by %.0f %%", 100 * *d.heldout_shrink);
  } else {
    s = "unexplained by the candidate effects";
  }
  s += fmt("   |   misfit chi2/dof %.2f on the fit data", d.gap_fit);
  if (d.gap_heldout) s += fmt(", %.2f held out", *d.gap_heldout);
  return s;
}

}  // namespace

DiagnosisPlotLayout diagnosis_plot_layout(int width, int height) {
  const double left = 84, right = width - 22.0, top = 74, bottom = height - 48.0, gap = 16;
  const double avail = bottom - top - gap, top_h = std::round(0.58 * avail);
  DiagnosisPlotLayout l;
  l.top = {left, top, right, top + top_h};
  l.bottom = {left, top + top_h + gap, right, bottom};
  return l;
}

PngCanvas render_diagnosis_plot(const update::GapDiagnosis& d, const DiagnosisPlotOptions& opt) {
  check_curve(d.before, "before");
  const update::GapCurve& after = d.after.f_hz.size() == d.before.f_hz.size() ? d.after : d.before;
  check_curve(after, "after");
  const auto& f = d.before.f_hz;
  const std::vector<double>& meas = d.before.measured_abs_ohm;
  const std::vector<double> z_before = model_abs(d.before), z_after = model_abs(after);

  PngCanvas cv(opt.width, opt.height);
  const DiagnosisPlotLayout L = diagnosis_plot_layout(opt.width, opt.height);

  // Axes. x: the curve's band; top y: every |Z| shown; bottom y: symmetric about 0 dB.
  const auto [fmin_it, fmax_it] = std::minmax_element(f.begin(), f.end());
  const double fmin = snap_down(*fmin_it), fmax = snap_up(*fmax_it);
  if (!(fmin > 0) || !(fmax > fmin))
    throw std::invalid_argument("render_diagnosis_plot: no frequency band to plot");
  const Axis xt{fmin, fmax, L.top.x0, L.top.x1, true},
      xb{fmin, fmax, L.bottom.x0, L.bottom.x1, true};
  double zlo = INFINITY, zhi = 0, rmax = 0;
  for (const auto* v : {&meas, &z_before, &z_after})
    for (double z : *v)
      if (z > 0 && std::isfinite(z)) zlo = std::min(zlo, z), zhi = std::max(zhi, z);
  for (std::size_t i = 0; i < f.size(); ++i)
    for (double r : {d.before.residual_db[i], after.residual_db[i], d.before.sigma_db[i]})
      if (std::isfinite(r)) rmax = std::max(rmax, std::abs(r));
  if (!(zhi > zlo)) throw std::invalid_argument("render_diagnosis_plot: no positive |Z| to plot");
  const double pad = std::pow(zhi / zlo, 0.05);
  const Axis yt{zlo / pad, zhi * pad, L.top.y1, L.top.y0, true};
  const double rlim = std::max(0.05, 1.08 * rmax);
  const Axis yb{-rlim, rlim, L.bottom.y1, L.bottom.y0, false};

  // Regions, shaded alternately in both panels.
  struct Band {
    double x0, x1;
    const update::GapRegion* region;
  };
  std::vector<Band> bands;
  for (const auto& g : d.regions) {
    const double lo = std::max(g.f_lo_hz, fmin), hi = std::min(g.f_hi_hz, fmax);
    if (!(hi > lo)) continue;
    bands.push_back({lo, hi, &g});
  }
  for (std::size_t k = 0; k < bands.size(); ++k) {
    const Rgba c = k % 2 ? kRegionB : kRegionA;
    for (const auto& [P, ax] : {std::pair{L.top, xt}, std::pair{L.bottom, xb}})
      cv.fill_rect(ax(bands[k].x0), P.y0, ax(bands[k].x1), P.y1, c);
  }

  // Grids.
  for (double t : log_minor(fmin, fmax)) {
    cv.line({std::round(xt(t)) + 0.5, L.top.y0}, {std::round(xt(t)) + 0.5, L.top.y1}, kMinorGrid);
    cv.line({std::round(xb(t)) + 0.5, L.bottom.y0}, {std::round(xb(t)) + 0.5, L.bottom.y1},
            kMinorGrid);
  }
  for (double t : log_labels(fmin, fmax)) {
    cv.line({std::round(xt(t)) + 0.5, L.top.y0}, {std::round(xt(t)) + 0.5, L.top.y1}, kGrid);
    cv.line({std::round(xb(t)) + 0.5, L.bottom.y0}, {std::round(xb(t)) + 0.5, L.bottom.y1}, kGrid);
    cv.line({std::round(xb(t)) + 0.5, L.bottom.y1}, {std::round(xb(t)) + 0.5, L.bottom.y1 + 4},
            kMuted);
    cv.text(xb(t), L.bottom.y1 + 6, t >= 1e3 ? fmt("%g kHz", t / 1e3) : fmt("%g Hz", t), kInk,
            FontSize::Normal, Align::Centre);
  }
  for (double t : log_minor(yt.lo, yt.hi))
    cv.line({L.top.x0, std::round(yt(t)) + 0.5}, {L.top.x1, std::round(yt(t)) + 0.5}, kMinorGrid);
  for (double t : log_labels(yt.lo, yt.hi)) {
    const double y = std::round(yt(t)) + 0.5;
    cv.line({L.top.x0, y}, {L.top.x1, y}, kGrid);
    cv.line({L.top.x0 - 4, y}, {L.top.x0, y}, kMuted);
    cv.text(L.top.x0 - 7, y - 6, tick_label(t, Scale::Log), kInk, FontSize::Normal, Align::Right);
  }
  for (double t : linear_ticks(-rlim, rlim, 7)) {
    const double y = std::round(yb(t)) + 0.5;
    cv.line({L.bottom.x0, y}, {L.bottom.x1, y}, t == 0.0 ? kZero : kGrid);
    cv.line({L.bottom.x0 - 4, y}, {L.bottom.x0, y}, kMuted);
    cv.text(L.bottom.x0 - 7, y - 6, tick_label(t, Scale::Linear), kInk, FontSize::Normal,
            Align::Right);
  }

  // Curves, clipped to their panels. Top: the model after as a wide halo, the
  // model before dashed, the measurement on top. Bottom: the noise band, then
  // the residuals before and after.
  cv.set_clip(L.top.x0, L.top.y0, L.top.x1, L.top.y1);
  cv.polyline(points(f, z_after, xt, yt), kAfter, 4.0);
  cv.polyline(points(f, z_before, xt, yt), kBefore, 1.8, 7.0);
  cv.polyline(points(f, meas, xt, yt), kMeasured, 1.4);
  cv.set_clip(L.bottom.x0, L.bottom.y0, L.bottom.x1, L.bottom.y1);
  {
    std::vector<double> px(f.size()), up(f.size()), dn(f.size());
    for (std::size_t i = 0; i < f.size(); ++i) {
      px[i] = xb(f[i]);
      up[i] = yb(d.before.sigma_db[i]);
      dn[i] = yb(-d.before.sigma_db[i]);
    }
    cv.fill_band(px, up, dn, kSigma);
  }
  cv.polyline(points(f, d.before.residual_db, xb, yb), kBefore, 1.5);
  cv.polyline(points(f, after.residual_db, xb, yb), kAfter, 1.8);
  cv.reset_clip();

  // Region names at the top of the |Z| panel, on a white halo (they may cross a
  // curve): horizontal in a band wide enough, else vertical, in frequency order
  // at least a line apart (nudged off narrow neighbouring bands, never dropped).
  {
    const double lh = cv.line_height();
    std::vector<double> xs(bands.size());
    std::vector<bool> flat(bands.size());
    std::vector<std::string> names(bands.size());
    for (std::size_t k = 0; k < bands.size(); ++k) {
      const auto& g = *bands[k].region;
      names[k] = g.name;
      if (g.share >= 0.1 && g.kind != "noise")
        names[k] += fmt(": %.0f %% of chi2, ", 100 * g.share) + g.kind;
      const double xa = xt(bands[k].x0), xz = xt(bands[k].x1);
      flat[k] = xz - xa > cv.text_width(names[k]) + 12;
      xs[k] = flat[k] ? (xa + xz) / 2 : std::round((xa + xz) / 2 - lh / 2);
    }
    for (std::size_t k = 1; k < xs.size(); ++k)  // left to right: keep a line apart
      if (!flat[k] && !flat[k - 1]) xs[k] = std::max(xs[k], xs[k - 1] + lh + 1);
    for (std::size_t k = xs.size(); k-- > 0;) {  // right to left: stay inside the panel
      if (flat[k]) continue;
      xs[k] = std::min(xs[k], L.top.x1 - lh - 2);
      if (k + 1 < xs.size() && !flat[k + 1]) xs[k] = std::min(xs[k], xs[k + 1] - lh - 1);
    }
    for (std::size_t k = 0; k < bands.size(); ++k) {
      const double w = cv.text_width(names[k]);
      const double x = xs[k], y = flat[k] ? L.top.y0 + 6 : L.top.y0 + 6 + w;
      const Align al = flat[k] ? Align::Centre : Align::Left;
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          if (dx || dy) cv.text(x + dx, y + dy, names[k], kHalo, FontSize::Normal, al, !flat[k]);
      cv.text(x, y, names[k], kInk, FontSize::Normal, al, !flat[k]);
    }
  }

  // Frames and axis labels.
  for (const PixelRect& P : {L.top, L.bottom}) {
    cv.line({P.x0 - 0.5, P.y0 - 0.5}, {P.x1 + 0.5, P.y0 - 0.5}, kMuted);
    cv.line({P.x0 - 0.5, P.y1 + 0.5}, {P.x1 + 0.5, P.y1 + 0.5}, kMuted);
    cv.line({P.x0 - 0.5, P.y0 - 0.5}, {P.x0 - 0.5, P.y1 + 0.5}, kMuted);
    cv.line({P.x1 + 0.5, P.y0 - 0.5}, {P.x1 + 0.5, P.y1 + 0.5}, kMuted);
  }
  cv.text(16, (L.top.y0 + L.top.y1) / 2, "|Z| (ohm)", kInk, FontSize::Normal, Align::Centre, true);
  cv.text(16, (L.bottom.y0 + L.bottom.y1) / 2, "residual (dB)", kInk, FontSize::Normal,
          Align::Centre, true);
  cv.text((L.bottom.x0 + L.bottom.x1) / 2, L.bottom.y1 + 26, "frequency", kInk, FontSize::Normal,
          Align::Centre);

  // Legend, bottom left of the |Z| panel (|Z| falls from the top left).
  {
    std::string added;
    for (const auto& a : d.added) added += (added.empty() ? "" : " + ") + a;
    const std::vector<std::pair<std::string, Rgba>> rows = {
        {"measured (" + d.fit_description + ")", kMeasured},
        {"model before: base refit (material + damping)", kBefore},
        {added.empty() ? "model after: no effect added" : "model after: + " + added, kAfter},
        {"+/-1 sigma of the measurement (residual panel)", kSigma},
    };
    double w = 0;
    for (const auto& r : rows) w = std::max(w, cv.text_width(r.first));
    const double lh = cv.line_height() + 5, bw = w + 52, bh = rows.size() * lh + 10;
    const double x0 = L.top.x0 + 8, y0 = L.top.y1 - bh - 8;  // below the capacitive line
    cv.fill_rect(x0, y0, x0 + bw, y0 + bh, {255, 255, 255, 225});
    cv.line({x0, y0 + 0.5}, {x0 + bw, y0 + 0.5}, kGrid);
    cv.line({x0, y0 + bh - 0.5}, {x0 + bw, y0 + bh - 0.5}, kGrid);
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const double y = y0 + 6 + k * lh, ym = std::round(y + lh / 2 - 3) + 0.5;
      if (k == 3)
        cv.fill_rect(x0 + 8, ym - 5, x0 + 38, ym + 5, rows[k].second);
      else if (k == 1)
        cv.polyline({{x0 + 8, ym}, {x0 + 38, ym}}, rows[k].second, 1.8, 7.0);
      else
        cv.line({x0 + 8, ym}, {x0 + 38, ym}, rows[k].second, k == 2 ? 4.0 : 1.6);
      cv.text(x0 + 46, y, rows[k].first, kInk);
    }
  }

  // Title with the verdict.
  std::string title = opt.title + " - verdict: " + d.verdict_effect;
  const FontSize ts =
      cv.text_width(title, FontSize::Large) <= opt.width - 30 ? FontSize::Large : FontSize::Normal;
  cv.text(16, 12, title, kInk, ts);
  cv.text(16, 14 + cv.line_height(ts) + 6, verdict_line(d), kMuted);
  return cv;
}

void write_diagnosis_png(const update::GapDiagnosis& d, const DiagnosisPlotOptions& opt,
                         const std::filesystem::path& file) {
  render_diagnosis_plot(d, opt).save_png(file);
}

}  // namespace piezo::report
