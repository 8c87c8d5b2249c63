#include "dsp/circuit_figures.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "numerics/complex_division.hpp"

namespace piezo::dsp {

namespace {

using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Golden-section search for the minimum of g on [a, b].
double golden_min(const std::function<double(double)>& g, double a, double b, int iterations = 80) {
  const double r = (std::sqrt(5.0) - 1.0) / 2.0;
  double c = b - r * (b - a), d = a + r * (b - a);
  double gc = g(c), gd = g(d);
  for (int i = 0; i < iterations && (b - a) > 1e-12 * std::abs(b); ++i) {
    if (gc < gd) {
      b = d;
      d = c;
      gd = gc;
      c = b - r * (b - a);
      gc = g(c);
    } else {
      a = c;
      c = d;
      gc = gd;
      d = a + r * (b - a);
      gd = g(d);
    }
  }
  return 0.5 * (a + b);
}

// The extremum of g on [a, b]: a grid, then golden section around the best point.
double grid_min(const std::function<double(double)>& g, double a, double b, int n = 400) {
  if (!(b > a)) return kNaN;
  double best = a, gb = g(a);
  int at = 0;
  for (int i = 1; i <= n; ++i) {
    const double x = a + (b - a) * i / n;
    const double gx = g(x);
    if (gx < gb) gb = gx, best = x, at = i;
  }
  if (at == 0 || at == n) return kNaN;  // no extremum inside: a monotonic stretch (a weak mode)
  const double h = (b - a) / n;
  return golden_min(g, std::max(a, best - h), std::min(b, best + h));
}

// A root of g between a and b (g(a), g(b) of opposite signs) by bisection.
double bisect(const std::function<double(double)>& g, double a, double b) {
  double ga = g(a);
  for (int i = 0; i < 200 && (b - a) > 1e-13 * std::abs(b); ++i) {
    const double m = 0.5 * (a + b);
    const double gm = g(m);
    if ((gm < 0) == (ga < 0)) {
      a = m;
      ga = gm;
    } else {
      b = m;
    }
  }
  return 0.5 * (a + b);
}

}  // namespace

double CircuitBranch::fs_hz() const { return 1.0 / (kTwoPi * std::sqrt(l_h * c_f)); }
double CircuitBranch::qm() const { return kTwoPi * fs_hz() * l_h / r_ohm; }

cd EquivalentCircuit::admittance_without_rs(double f_hz) const {
  const cd s(0.0, kTwoPi * f_hz);
  cd y = s * c0_f * cd(1.0, -tan_delta);
  // 1/(sC) = −j/(ωC), then the branch's admittance by Smith's division
  // (numerics/complex_division.hpp: no libgcc call in the circuit fits' loop).
  for (const auto& b : branches)
    y += numerics::reciprocal(b.r_ohm + s * b.l_h + cd(0.0, -1.0 / (s.imag() * b.c_f)));
  return y;
}

cd EquivalentCircuit::impedance(double f_hz) const { return numerics::reciprocal(admittance_without_rs(f_hz)) + rs_ohm; }

double EquivalentCircuit::lossless_susceptance(double f_hz) const {
  const double w = kTwoPi * f_hz;
  double b = w * c0_f;
  for (const auto& br : branches) b -= 1.0 / (w * br.l_h - 1.0 / (w * br.c_f));
  return b;
}

namespace {

// The parallel resonances fp_k of the lossless network, one above each fs_k:
// its susceptance runs from −∞ just above fs_k to +∞ just below fs_{k+1} (or
// as ωC0 → ∞ above the last): one zero between (Foster's reactance theorem).
// A weak branch between a strong one's fs and fp (C_j below a tenth of C_k,
// fs_j below the strong branch's one-branch fp = fs_k·√(1 + C_k/C0)) would
// take that zero, and the strong mode's fp would be reported at the weak
// one's: such a "guest" lies where its host's background is inductive, has no
// parallel resonance above its fs (fp NaN), and its host's fp is the zero of
// the network with the guests standing as their static capacitance C_j.
struct Resonances {
  std::vector<double> fp;
  std::vector<int> host;  // a guest's host branch; −1 for the others
  // The next branch that is not a guest of this one (its fs bounds the
  // mode's window and its |Z| maximum); −1 above the last.
  std::vector<int> next;
};

Resonances parallel_resonances(const EquivalentCircuit& c) {
  const std::size_t n = c.branches.size();
  Resonances r;
  r.fp.assign(n, kNaN);
  r.host.assign(n, -1);
  r.next.assign(n, -1);
  for (std::size_t k = 0; k < n; ++k) {
    const auto& b = c.branches[k];
    if (r.host[k] >= 0 || !(c.c0_f > 0)) continue;
    const double fp1 = b.fs_hz() * std::sqrt(1.0 + b.c_f / c.c0_f);
    for (std::size_t j = k + 1; j < n && c.branches[j].fs_hz() < fp1; ++j)
      if (c.branches[j].c_f < 0.1 * b.c_f) r.host[j] = static_cast<int>(k);
  }
  for (std::size_t k = 0; k < n; ++k) {
    for (std::size_t j = k + 1; j < n; ++j)
      if (r.host[j] != static_cast<int>(k) || r.host[k] >= 0) {
        r.next[k] = static_cast<int>(j);
        break;
      }
    if (r.host[k] >= 0) continue;
    EquivalentCircuit e = c;  // the guests of k as their static capacitance
    e.branches.clear();
    for (std::size_t j = 0; j < n; ++j) {
      if (r.host[j] == static_cast<int>(k))
        e.c0_f += c.branches[j].c_f;
      else
        e.branches.push_back(c.branches[j]);
    }
    auto bsus = [&](double f) { return e.lossless_susceptance(f); };
    const double fs = c.branches[k].fs_hz();
    const double lo = fs * (1 + 1e-12);
    double hi = r.next[k] >= 0 ? c.branches[static_cast<std::size_t>(r.next[k])].fs_hz() * (1 - 1e-12) : 2 * fs;
    if (r.next[k] < 0)
      while (bsus(hi) < 0 && hi < fs * 1e6) hi *= 2;
    r.fp[k] = hi > lo && bsus(lo) < 0 && bsus(hi) > 0 ? bisect(bsus, lo, hi) : kNaN;
  }
  return r;
}

// The window of branch k: half-way to the neighbours (fp of the one below, or
// its fs when it has none; fs of the next one that is not a guest of k); the
// outer modes open to the band's ends.
std::pair<double, double> mode_window(const EquivalentCircuit& c, const Resonances& r, std::size_t k) {
  const double fs = c.branches[k].fs_hz();
  double lo = 0.0;
  if (k > 0) {
    const double below = std::isfinite(r.fp[k - 1]) && r.fp[k - 1] < fs ? r.fp[k - 1] : c.branches[k - 1].fs_hz();
    lo = 0.5 * (below + fs);
  }
  double hi = std::numeric_limits<double>::infinity();
  if (r.next[k] >= 0) {
    const double nfs = c.branches[static_cast<std::size_t>(r.next[k])].fs_hz();
    hi = 0.5 * ((std::isfinite(r.fp[k]) && r.fp[k] < nfs ? r.fp[k] : fs) + nfs);
  }
  return {lo, hi};
}

CircuitModeFigures figures_of(const EquivalentCircuit& c, const Resonances& res, std::size_t k) {
  CircuitModeFigures m;
  const auto& b = c.branches[k];
  const double fs = b.fs_hz(), q = b.qm(), fp = res.fp[k];
  m.fs_hz.value = fs;
  m.fp_hz.value = fp;
  m.qm_branch.value = q;
  m.r1_ohm.value = b.r_ohm;
  m.l1_h.value = b.l_h;
  m.c1_f.value = b.c_f;
  std::tie(m.window_lo_hz, m.window_hi_hz) = mode_window(c, res, k);
  if (!std::isfinite(fp)) return m;
  m.k_eff_ieee176.value = std::sqrt(std::max(0.0, 1.0 - std::pow(fs / fp, 2)));
  // |Z| extrema of the lossy network: the minimum below fp, the maximum above it.
  const double span = (fp - fs) + 3.0 * fs / q;
  const double a = std::max(std::max(m.window_lo_hz, 1e-9 * fs), fs - span);
  const double next_fs = res.next[k] >= 0 ? c.branches[static_cast<std::size_t>(res.next[k])].fs_hz() : kNaN;
  const double z_hi = std::isfinite(next_fs) ? next_fs : fp + span;
  auto absz = [&](double f) { return std::abs(c.impedance(f)); };
  m.fm_hz.value = grid_min(absz, a, fp);
  const double fm = m.fm_hz.value;
  m.fn_hz.value = grid_min([&](double f) { return -absz(f); }, fm, z_hi);
  const double fn = m.fn_hz.value;
  if (std::isfinite(fm) && std::isfinite(fn) && fn > fm)
    m.k_eff_en50324.value = std::sqrt(std::max(0.0, 1.0 - std::pow(fm / fn, 2)));
  // Zero phase: Im Z rises through 0 near fm (fr) and falls through 0 near fn (fa).
  if (std::isfinite(fm) && std::isfinite(fn) && fn > fm) {
    auto imz = [&](double f) { return c.impedance(f).imag(); };
    const double g0 = fm - 0.5 * (fn - fm), g1 = fn + 0.5 * (fn - fm);
    const int n = 800;
    double prev_f = std::max(g0, 1e-9 * fs), prev = imz(prev_f);
    for (int i = 1; i <= n; ++i) {
      const double f = g0 + (g1 - g0) * i / n;
      if (f <= prev_f) continue;
      const double v = imz(f);
      if (prev < 0 && v >= 0 && !std::isfinite(m.fr_hz.value)) m.fr_hz.value = bisect(imz, prev_f, f);
      if (prev > 0 && v <= 0 && std::isfinite(m.fr_hz.value) && !std::isfinite(m.fa_hz.value))
        m.fa_hz.value = bisect([&](double x) { return -imz(x); }, prev_f, f);
      prev_f = f;
      prev = v;
    }
  }
  // Bandwidth Qm: the conductance peak near fs and its half-power points.
  auto g = [&](double f) { return numerics::reciprocal(c.impedance(f)).real(); };
  const double fg = grid_min([&](double f) { return -g(f); }, a, fp);
  if (std::isfinite(fg)) {
    const double half = 0.5 * g(fg);
    auto above = [&](double f) { return g(f) - half; };
    double l = fg, h = fg;
    const double step = std::max(fs / q / 8.0, 1e-6 * fs);
    int guard = 0;
    while (l > a && above(l) > 0 && guard++ < 100000) l -= step;
    guard = 0;
    while (h < z_hi && above(h) > 0 && guard++ < 100000) h += step;
    if (above(l) < 0 && above(h) < 0) {
      const double f1 = bisect(above, l, fg), f2 = bisect([&](double x) { return -above(x); }, fg, h);
      if (f2 > f1) m.qm_bandwidth.value = fg / (f2 - f1);
    }
  }
  return m;
}

}  // namespace

// Every figure of every mode, in one vector (for the finite differences).
std::vector<double> circuit_figure_vector(const std::vector<CircuitModeFigures>& ms) {
  std::vector<double> v;
  for (const auto& m : ms)
    for (const auto& [name, f] : named_figures(m)) v.push_back(f->value);
  return v;
}

std::vector<Figure*> circuit_figure_slots(std::vector<CircuitModeFigures>& ms) {
  std::vector<Figure*> v;
  for (auto& m : ms)
    for (const auto& [name, f] : named_figures(m)) v.push_back(f);
  return v;
}

std::vector<CircuitModeFigures> all_circuit_figures(const EquivalentCircuit& c) {
  const auto fp = parallel_resonances(c);
  std::vector<CircuitModeFigures> ms;
  for (std::size_t k = 0; k < c.branches.size(); ++k) ms.push_back(figures_of(c, fp, k));
  return ms;
}


std::vector<std::pair<const char*, Figure*>> named_figures(CircuitModeFigures& m) {
  return {{"fs_hz", &m.fs_hz},
          {"fp_hz", &m.fp_hz},
          {"fm_hz", &m.fm_hz},
          {"fn_hz", &m.fn_hz},
          {"fr_hz", &m.fr_hz},
          {"fa_hz", &m.fa_hz},
          {"k_eff_ieee176", &m.k_eff_ieee176},
          {"k_eff_en50324", &m.k_eff_en50324},
          {"qm_branch", &m.qm_branch},
          {"qm_bandwidth", &m.qm_bandwidth},
          {"r1_ohm", &m.r1_ohm},
          {"l1_h", &m.l1_h},
          {"c1_f", &m.c1_f}};
}

std::vector<std::pair<const char*, const Figure*>> named_figures(const CircuitModeFigures& m) {
  std::vector<std::pair<const char*, const Figure*>> out;
  for (const auto& [name, f] : named_figures(const_cast<CircuitModeFigures&>(m))) out.emplace_back(name, f);
  return out;
}

CircuitModeFigures circuit_mode_figures(const EquivalentCircuit& c, std::size_t k) {
  if (k >= c.branches.size()) throw std::invalid_argument("circuit_mode_figures: no such branch");
  return figures_of(c, parallel_resonances(c), k);
}

}  // namespace piezo::dsp
