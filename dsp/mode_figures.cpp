#include "dsp/mode_figures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <stdexcept>

namespace piezo::dsp {

namespace {
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

std::string fmt(const char* f, double a, double b = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, f, a, b);
  return buf;
}

Eigen::Index first_at_or_above(const Eigen::VectorXd& f, double x) {
  return static_cast<Eigen::Index>(std::lower_bound(f.data(), f.data() + f.size(), x) - f.data());
}
Eigen::Index last_at_or_below(const Eigen::VectorXd& f, double x) {
  return static_cast<Eigen::Index>(std::upper_bound(f.data(), f.data() + f.size(), x) - f.data()) -
         1;
}

double fs_of(const BvdParams& p) { return 1.0 / (kTwoPi * std::sqrt(p.l1_h * p.c1_f)); }
double fp_of(const BvdParams& p) { return fs_of(p) * std::sqrt(1.0 + p.c1_f / p.c0_f); }
double qm_of(const BvdParams& p) { return 1.0 / (kTwoPi * fs_of(p) * p.r1_ohm * p.c1_f); }

// σ of a function with gradient g (in ln R1, ln L1, ln C1, ln C0) under cov.
double sigma_of(const Eigen::Vector4d& g, const Eigen::Matrix4d& cov) {
  return std::sqrt(std::max(0.0, g.dot(cov * g)));
}

struct Slot {
  Feature fm, fn;  // fn.f_hz NaN when no maximum is paired
  std::optional<BvdParams> p;
  BvdFit fit;
  Eigen::Index lo = 0, hi = 0;  // fit window (grid indices)
  std::vector<std::string> notes;
  // Approximate fs, fp for window clipping before / without a fit.
  double fs() const { return p ? fs_of(*p) : fm.f_hz; }
  double fp() const {
    if (p) return fp_of(*p);
    return std::isfinite(fn.f_hz) ? fn.f_hz : fm.f_hz;
  }
};

// Motional admittance of the fitted modes within `neighbours` of `skip` (not
// `skip` itself), on the grid points lo..hi (zero elsewhere: no reader looks there).
Eigen::VectorXcd background(const Eigen::VectorXd& f, const std::vector<Slot>& s,
                            std::size_t skip, Eigen::Index lo, Eigen::Index hi, int neighbours) {
  Eigen::VectorXcd yb = Eigen::VectorXcd::Zero(f.size());
  const std::size_t n = static_cast<std::size_t>(std::max(neighbours, 0));
  const std::size_t first = skip > n ? skip - n : 0, last = std::min(s.size() - 1, skip + n);
  for (std::size_t j = first; j <= last; ++j)
    if (j != skip && s[j].p)
      for (Eigen::Index k = lo; k <= hi; ++k) yb[k] += s[j].p->motional_admittance(f[k]);
  return yb;
}

// Start values: the circle through the conductance peak's points (G ≥ G_max/4, at least 5).
std::optional<BvdParams> start_values(const Eigen::VectorXd& f, const Eigen::VectorXcd& y,
                                      Eigen::Index lo, Eigen::Index hi,
                                      std::vector<std::string>& notes) {
  if (hi - lo < 4) {
    notes.push_back("too few grid points around the resonance for a circle fit");
    return std::nullopt;
  }
  Eigen::Index i = lo;
  for (Eigen::Index k = lo; k <= hi; ++k)
    if (y[k].real() > y[i].real()) i = k;
  const double quarter = 0.25 * y[i].real();
  Eigen::Index a = i, b = i;
  while (a > lo && y[a - 1].real() >= quarter) --a;
  while (b < hi && y[b + 1].real() >= quarter) ++b;
  while (b - a < 4 && (a > lo || b < hi)) {
    if (a > lo) --a;
    if (b - a < 4 && b < hi) ++b;
  }
  try {
    return bvd_start_from_circle(f, y, a, b);
  } catch (const std::invalid_argument& e) {
    notes.push_back(std::string("circle fit: ") + e.what());
    return std::nullopt;
  }
}

void fit_slot(const Eigen::VectorXd& f, const Eigen::VectorXcd& z, const Eigen::VectorXd& zs,
              const Eigen::VectorXcd& y, std::vector<Slot>& s, std::size_t k,
              const ModeFigureOptions& opt) {
  Slot& m = s[k];
  // Neighbour bounds: half-way to fp of the mode below and fs of the mode above.
  const double lo_bound = k > 0 ? 0.5 * (s[k - 1].fp() + m.fs()) : f[0];
  const double hi_bound = k + 1 < s.size() ? 0.5 * (m.fp() + s[k + 1].fs()) : f[f.size() - 1];
  const Eigen::VectorXcd yb =
      opt.subtract_other_modes
          ? background(f, s, k, first_at_or_above(f, lo_bound), last_at_or_below(f, hi_bound),
                       opt.background_neighbours)
          : Eigen::VectorXcd::Zero(f.size());
  if (!m.p) {
    m.notes.clear();
    const double up = std::isfinite(m.fn.f_hz) ? 0.5 * (m.fm.f_hz + m.fn.f_hz) : hi_bound;
    const Eigen::VectorXcd ya = y - yb;
    m.p = start_values(f, ya, first_at_or_above(f, lo_bound), last_at_or_below(f, up), m.notes);
    if (!m.p) return;
  }
  const double fs = fs_of(*m.p), df = fs / qm_of(*m.p);
  const double lo_f = std::max(lo_bound, fs - opt.window_bandwidths * df);
  const double hi_f = std::min(hi_bound, fp_of(*m.p) + opt.window_bandwidths * df);
  m.lo = first_at_or_above(f, lo_f);
  m.hi = last_at_or_below(f, hi_f);
  if (m.hi - m.lo < 5) {
    m.notes.push_back("fewer than 6 grid points in the fit window");
    return;
  }
  try {
    m.fit = fit_bvd(f, z, zs, yb, m.lo, m.hi, *m.p, opt.fit);
    m.p = m.fit.p;
    // A branch that resonates outside its own window fitted something else
    // (a grid coarser than the resonance, a mode too weak): no figures.
    const double fs_fit = fs_of(*m.p);
    if (!(fs_fit >= f[m.lo] && fs_fit <= f[m.hi]) || !std::isfinite(fp_of(*m.p))) {
      m.notes.push_back("the BVD fit left its window (grid too coarse for the resonance?)");
      m.p.reset();
      m.fit = BvdFit{};
    }
  } catch (const std::invalid_argument& e) {
    m.notes.push_back(std::string("BVD fit: ") + e.what());
  }
}

double rel_change(const BvdParams& a, const BvdParams& b) {
  return std::max({std::abs(a.r1_ohm / b.r1_ohm - 1), std::abs(a.l1_h / b.l1_h - 1),
                   std::abs(a.c1_f / b.c1_f - 1), std::abs(a.c0_f / b.c0_f - 1)});
}

ModeFigures figures_of(const Slot& m, const Eigen::VectorXd& f, const Eigen::VectorXcd& y_adj,
                       const Eigen::VectorXd& g_sigma, const ModeFigureOptions& opt) {
  ModeFigures out;
  out.notes = m.notes;
  out.fm_hz = {m.fm.f_hz, m.fm.sigma_hz};
  out.fn_hz = {m.fn.f_hz, m.fn.sigma_hz};
  if (!std::isfinite(m.fn.f_hz)) out.notes.push_back("no |Z| maximum paired with this minimum");
  if (!m.p || m.fit.points == 0) return out;
  const BvdParams& p = *m.p;
  const Eigen::Matrix4d& c = m.fit.cov_ln;
  out.fit = m.fit;
  out.window_lo_hz = f[m.lo];
  out.window_hi_hz = f[m.hi];
  if (!m.fit.converged) out.notes.push_back("BVD fit: " + m.fit.message);
  const Eigen::Index is = std::clamp<Eigen::Index>(first_at_or_above(f, fs_of(p)), 1, f.size() - 1);
  if (f[is] - f[is - 1] > 0.5 * fs_of(p) / qm_of(p))
    out.notes.push_back(
        "grid step above half the resonance bandwidth: R1, L1 and Qm are poorly resolved");
  out.r1_ohm = {p.r1_ohm, m.fit.sigma.r1_ohm};
  out.l1_h = {p.l1_h, m.fit.sigma.l1_h};
  out.c1_f = {p.c1_f, m.fit.sigma.c1_f};
  out.c0_f = {p.c0_f, m.fit.sigma.c0_f};
  // Gradients of the derived figures in (ln R1, ln L1, ln C1, ln C0).
  const double fs = fs_of(p), fp = fp_of(p), k2 = p.c1_f / (p.c0_f + p.c1_f), q = qm_of(p);
  out.fs_hz = {fs, fs * sigma_of({0, -0.5, -0.5, 0}, c)};
  out.fp_hz = {fp, fp * sigma_of({0, -0.5, -0.5 + 0.5 * k2, -0.5 * k2}, c)};
  out.k_eff2 = {k2, sigma_of({0, 0, k2 * (1 - k2), -k2 * (1 - k2)}, c)};
  out.k_eff = {std::sqrt(k2), out.k_eff2.sigma / (2 * std::sqrt(k2))};
  out.qm_branch = {q, q * sigma_of({-1, 0.5, -0.5, 0}, c)};
  if (std::isfinite(opt.mean_diameter_m))
    out.frequency_constant_hz_m = {fs * opt.mean_diameter_m, out.fs_hz.sigma * opt.mean_diameter_m};
  // The bandwidth method on the measured conductance (other modes' branches
  // removed), from the window's low edge to half-way to fp.
  const Eigen::Index hi = std::min(m.hi, last_at_or_below(f, 0.5 * (fs + fp)));
  if (hi - m.lo >= 2) {
    out.conductance = conductance_peak(f, y_adj.real(), g_sigma, m.lo, hi);
  } else {
    out.conductance.message = "fewer than 3 grid points between the window's edge and (fs + fp)/2";
  }
  if (out.conductance.ok) {
    out.qm_bandwidth = {out.conductance.qm, out.conductance.qm_sigma};
    const double s = std::hypot(out.qm_bandwidth.sigma, out.qm_branch.sigma);
    const double d = std::abs(out.qm_bandwidth.value - q);
    if (std::isfinite(s) ? d > 3 * s && d > 0.02 * q : d > 0.05 * q)
      out.notes.push_back(fmt("Qm from the branch (%.4g) and from the bandwidth (%.4g) disagree", q,
                              out.qm_bandwidth.value));
  } else {
    out.notes.push_back("bandwidth Qm: " + out.conductance.message);
  }
  return out;
}

}  // namespace

ModeFiguresResult mode_figures(const Eigen::VectorXd& f, const Eigen::VectorXcd& z,
                               const Eigen::VectorXd& z_sigma, const ModeFigureOptions& opt) {
  if (z.size() != f.size() || (z_sigma.size() && z_sigma.size() != f.size()))
    throw std::invalid_argument("mode_figures: f, z and z_sigma sizes differ");
  if (f.size() < 5) throw std::invalid_argument("mode_figures: need at least 5 grid points");
  for (Eigen::Index k = 1; k < f.size(); ++k)
    if (!(f[k] > f[k - 1])) throw std::invalid_argument("mode_figures: f must increase");
  if (!(f[0] > 0)) throw std::invalid_argument("mode_figures: f must be > 0");
  ModeFiguresResult res;
  const Eigen::VectorXcd y = z.cwiseInverse();
  Eigen::VectorXd g_sigma;  // σ of Re Y: |δY| = |Y|²|δZ|, half the variance per component
  if (z_sigma.size()) g_sigma = y.cwiseAbs2().cwiseProduct(z_sigma) / std::sqrt(2.0);

  // Modes: each |Z| minimum, paired with the first maximum before the next minimum.
  const auto feats = find_features(f, z, z_sigma, opt.features);
  std::vector<Slot> s;
  for (std::size_t k = 0; k < feats.resonances.size(); ++k) {
    Slot m;
    m.fm = feats.resonances[k];
    const double next = k + 1 < feats.resonances.size() ? feats.resonances[k + 1].f_hz : INFINITY;
    for (const auto& a : feats.antiresonances)
      if (a.f_hz > m.fm.f_hz && a.f_hz < next) {
        m.fn = a;
        break;
      }
    s.push_back(m);
  }
  if (s.empty()) res.notes.push_back("no resonance (|Z| minimum) found on the grid");
  if (opt.max_modes >= 0 && s.size() > static_cast<std::size_t>(opt.max_modes)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "%zu |Z| minima on the grid: the lowest %d fitted, none from %.6g Hz up",
                  s.size(), opt.max_modes, s[static_cast<std::size_t>(opt.max_modes)].fm.f_hz);
    res.notes.push_back(buf);
    s.resize(static_cast<std::size_t>(opt.max_modes));
  }

  // Gauss–Seidel sweeps: each mode fitted with the others' latest branches as background.
  const int sweeps = opt.subtract_other_modes ? std::max(1, opt.max_sweeps) : 1;
  for (res.sweeps = 1; res.sweeps <= sweeps && !s.empty(); ++res.sweeps) {
    double change = 0;
    for (std::size_t k = 0; k < s.size(); ++k) {
      const auto before = s[k].p;
      fit_slot(f, z, z_sigma, y, s, k, opt);
      change = std::max(change, before && s[k].p ? rel_change(*s[k].p, *before) : INFINITY);
    }
    if (change < opt.sweep_tolerance) break;
  }
  res.sweeps = std::min(res.sweeps, sweeps);
  for (std::size_t k = 0; k < s.size(); ++k) {
    // figures_of reads the window m.lo..m.hi only.
    const Eigen::VectorXcd yb =
        opt.subtract_other_modes && s[k].hi >= s[k].lo
            ? background(f, s, k, s[k].lo, s[k].hi, opt.background_neighbours)
            : Eigen::VectorXcd::Zero(f.size());
    res.modes.push_back(figures_of(s[k], f, y - yb, g_sigma, opt));
  }

  // Free capacitance C^T and tan δ (EN 50324-2): Y = jωC^T(1 − j tan δ), Y linear
  // between the two grid points around the reference frequency.
  double fr = opt.reference_hz;
  if (fr < f[0] || fr > f[f.size() - 1]) {
    fr = f[0];
    res.notes.push_back(
        fmt("C^T and tan delta at %.6g Hz, the grid's lowest frequency (not %.6g Hz)", fr,
            opt.reference_hz));
  }
  const Eigen::Index i1 =
      std::min<Eigen::Index>(f.size() - 1, std::max<Eigen::Index>(1, first_at_or_above(f, fr)));
  const double t = (fr - f[i1 - 1]) / (f[i1] - f[i1 - 1]);
  const cd yr = (1 - t) * y[i1 - 1] + t * y[i1];
  const double w = kTwoPi * fr;
  res.reference_used_hz = fr;
  res.free_capacitance_f.value = yr.imag() / w;
  res.tan_delta.value = yr.real() / yr.imag();
  if (z_sigma.size()) {
    const double sy = std::hypot((1 - t) * g_sigma[i1 - 1], t * g_sigma[i1]);  // per component
    res.free_capacitance_f.sigma = sy / w;
    res.tan_delta.sigma = std::hypot(sy, res.tan_delta.value * sy) / std::abs(yr.imag());
  }
  if (!res.modes.empty() && res.modes.front().fs_hz.value < 3.0 * fr)
    res.notes.push_back(
        "the reference frequency is within a factor 3 of the first resonance: "
        "C^T is not the free (low-frequency) capacitance");

  // Hoop mode: given, or the most strongly coupled one.
  int hoop = opt.hoop_mode;
  if (hoop < 0) {
    double best = -1;
    for (std::size_t k = 0; k < res.modes.size(); ++k)
      if (res.modes[k].k_eff2.value > best) {
        best = res.modes[k].k_eff2.value;
        hoop = static_cast<int>(k);
      }
  }
  if (hoop >= 0 && hoop < static_cast<int>(res.modes.size())) {
    res.hoop_mode = hoop;
    res.frequency_constant_hz_m = res.modes[static_cast<std::size_t>(hoop)].frequency_constant_hz_m;
  } else if (opt.hoop_mode >= 0) {
    res.notes.push_back(fmt("hoop mode %.0f does not exist", opt.hoop_mode));
  }
  return res;
}

}  // namespace piezo::dsp
