#include "dsp/circuit_adequacy.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <complex>
#include <numbers>
#include <sstream>

namespace piezo::dsp {

namespace {

using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

std::string fmt(double v, int prec = 4) {
  std::ostringstream s;
  s.precision(prec);
  s << v;
  return s.str();
}

std::string pct(double v) { return fmt(100.0 * v, 3) + " %"; }

double median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// The grid step around point i (the larger of its two neighbours' spacings).
double grid_step(const Eigen::VectorXd& f, Eigen::Index i) {
  const Eigen::Index n = f.size();
  double s = 0;
  if (i > 0) s = std::max(s, f[i] - f[i - 1]);
  if (i + 1 < n) s = std::max(s, f[i + 1] - f[i]);
  return s;
}

double grid_step_at(const Eigen::VectorXd& f, double x) {
  const Eigen::Index n = f.size();
  Eigen::Index i = std::lower_bound(f.data(), f.data() + n, x) - f.data();
  i = std::clamp<Eigen::Index>(i, 0, n - 1);
  return grid_step(f, i);
}

// The vertex of the parabola through (f[i-1..i+1], y), inside that span; the
// grid point itself at an edge.
double parabola_vertex(const Eigen::VectorXd& f, const Eigen::VectorXd& y, Eigen::Index i) {
  if (i <= 0 || i + 1 >= f.size()) return f[std::clamp<Eigen::Index>(i, 0, f.size() - 1)];
  const double x0 = f[i - 1], x1 = f[i], x2 = f[i + 1];
  const double y0 = y[i - 1], y1 = y[i], y2 = y[i + 1];
  const double d0 = (y1 - y0) / (x1 - x0), d1 = (y2 - y1) / (x2 - x1);
  const double a = (d1 - d0) / (x2 - x0);
  if (!(a != 0) || !std::isfinite(a)) return x1;
  const double v = 0.5 * (x0 + x1) - d0 / (2 * a);
  return std::clamp(v, x0, x2);
}

// The data's extremum (maximum of y) in [lo, hi]: the vertex of the parabola
// through the highest point and its neighbours; NaN when the highest point
// lies on the interval's edge while the data go on beyond it (a slope, no
// extremum inside).
double data_maximum(const Eigen::VectorXd& f, const Eigen::VectorXd& y, double lo, double hi) {
  const Eigen::Index n = f.size();
  const Eigen::Index a = std::lower_bound(f.data(), f.data() + n, lo) - f.data();
  const Eigen::Index b = (std::upper_bound(f.data(), f.data() + n, hi) - f.data()) - 1;
  if (b - a < 2) return kNaN;
  Eigen::Index at = a;
  for (Eigen::Index i = a; i <= b; ++i)
    if (y[i] > y[at]) at = i;
  if ((at == a && a > 0) || (at == b && b + 1 < n) || at == 0 || at == n - 1) return kNaN;
  return parabola_vertex(f, y, at);
}

// Lag-1 autocorrelation of a residual sequence (complex: both components).
struct Lag1 {
  double rho = kNaN;
  int points = 0;
};
Lag1 lag1(const std::vector<cd>& r) {
  double num = 0, den = 0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    den += std::norm(r[i]);
    if (i + 1 < r.size()) num += r[i].real() * r[i + 1].real() + r[i].imag() * r[i + 1].imag();
  }
  Lag1 out;
  out.points = static_cast<int>(r.size());
  if (r.size() >= 3 && den > 0) out.rho = num / den;
  return out;
}

void add_reason(CircuitModeFigures& m, const std::string& why) {
  m.status = "unreliable";
  if (std::find(m.reasons.begin(), m.reasons.end(), why) == m.reasons.end()) m.reasons.push_back(why);
}

void widen(Figure& x, double sys) {
  if (std::isfinite(x.value) && std::isfinite(sys) && sys > 0)
    x.sigma = std::isfinite(x.sigma) ? std::hypot(x.sigma, sys) : sys;
}

}  // namespace

double scatter_noise_rel(const Eigen::VectorXd& f, const Eigen::VectorXcd& z, bool magnitude_only) {
  const Eigen::Index n = f.size();
  if (n < 5) return kNaN;
  std::vector<double> e;
  e.reserve(static_cast<std::size_t>(2 * n));
  for (Eigen::Index i = 1; i + 1 < n; ++i) {
    const double x0 = std::log(f[i - 1]), x1 = std::log(f[i]), x2 = std::log(f[i + 1]);
    if (!(x2 > x0)) continue;
    const double a = (x2 - x1) / (x2 - x0), b = (x1 - x0) / (x2 - x0);
    const double norm = std::sqrt(1.0 + a * a + b * b);
    if (magnitude_only) {
      const double d = a * std::log(std::abs(z[i]) / std::abs(z[i - 1])) + b * std::log(std::abs(z[i]) / std::abs(z[i + 1]));
      e.push_back(std::abs(d) / norm);
    } else {
      // ln Z_i minus the line through ln Z_{i-1}, ln Z_{i+1}: a·ln(Z_i/Z_{i-1}) + b·ln(Z_i/Z_{i+1}).
      const cd d = a * std::log(z[i] / z[i - 1]) + b * std::log(z[i] / z[i + 1]);
      e.push_back(std::abs(d.real()) / norm);
      e.push_back(std::abs(d.imag()) / norm);
    }
  }
  if (e.size() < 3) return kNaN;
  return std::max(1e-6, 1.4826 * median(std::move(e)));
}

std::vector<ConductanceDataPeak> prominent_conductance_peaks(const Eigen::VectorXd& f, const Eigen::VectorXcd& z,
                                                             bool magnitude_only, double noise_rel,
                                                             double min_noise, double min_share) {
  const Eigen::Index n = f.size();
  std::vector<ConductanceDataPeak> out;
  if (n < 3) return out;
  Eigen::VectorXd g(n), ya(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    ya[i] = 1.0 / std::abs(z[i]);
    g[i] = magnitude_only ? ya[i] : (1.0 / z[i]).real();
  }
  const double gmax = g.maxCoeff();
  // Nearest strictly higher point on each side (monotonic stack), and the
  // minimum of g between (a sparse table of range minima).
  std::vector<Eigen::Index> left(static_cast<std::size_t>(n), -1), right(static_cast<std::size_t>(n), n);
  {
    std::vector<Eigen::Index> st;
    for (Eigen::Index i = 0; i < n; ++i) {
      while (!st.empty() && g[st.back()] <= g[i]) st.pop_back();
      left[static_cast<std::size_t>(i)] = st.empty() ? -1 : st.back();
      st.push_back(i);
    }
    st.clear();
    for (Eigen::Index i = n - 1; i >= 0; --i) {
      while (!st.empty() && g[st.back()] <= g[i]) st.pop_back();
      right[static_cast<std::size_t>(i)] = st.empty() ? n : st.back();
      st.push_back(i);
    }
  }
  std::vector<std::vector<double>> table{std::vector<double>(g.data(), g.data() + n)};
  for (Eigen::Index w = 1; 2 * w <= n; w *= 2) {
    const auto& prev = table.back();
    std::vector<double> next(static_cast<std::size_t>(n - 2 * w + 1));
    for (std::size_t i = 0; i < next.size(); ++i) next[i] = std::min(prev[i], prev[i + static_cast<std::size_t>(w)]);
    table.push_back(std::move(next));
  }
  auto range_min = [&](Eigen::Index a, Eigen::Index b) {  // inclusive, a <= b
    const auto len = static_cast<unsigned long>(b - a + 1);
    const int k = static_cast<int>(std::bit_width(len)) - 1;
    const auto& t = table[static_cast<std::size_t>(k)];
    return std::min(t[static_cast<std::size_t>(a)], t[static_cast<std::size_t>(b - (Eigen::Index(1) << k) + 1)]);
  };
  for (Eigen::Index i = 1; i + 1 < n; ++i) {
    if (!(g[i] > g[i - 1] && g[i] >= g[i + 1])) continue;
    const Eigen::Index l = left[static_cast<std::size_t>(i)], r = right[static_cast<std::size_t>(i)];
    const double lmin = range_min(l < 0 ? 0 : l, i), rmin = range_min(i, r >= n ? n - 1 : r);
    const double col = std::max(lmin, rmin);
    const double prom = g[i] - col;
    const double noise = std::isfinite(noise_rel) ? noise_rel * ya[i] : 0.0;
    if (!(prom >= min_noise * noise && prom >= min_share * gmax)) continue;
    const double level = g[i] - 0.5 * prom;
    Eigen::Index a = i, b = i;
    while (a > 0 && g[a] > level) --a;
    while (b + 1 < n && g[b] > level) ++b;
    out.push_back({i, f[i], g[i], prom, 0.5 * (f[b] - f[a])});
  }
  std::sort(out.begin(), out.end(), [](const auto& x, const auto& y) { return x.prominence_s > y.prominence_s; });
  return out;
}

void assess_circuit_fit(const Eigen::VectorXd& f, const Eigen::VectorXcd& z, CircuitFit& fit, const AdequacyOptions& opt) {
  const Eigen::Index n = f.size();
  if (n < 2 || (opt.data_checks && (n < 3 || z.size() != n))) return;
  const bool mag = fit.magnitude_only;
  const auto& c = fit.circuit;

  // The data's own noise, the residual against it, and its correlation.
  std::vector<cd> res;
  if (opt.data_checks) {
    fit.noise_scatter_rel = scatter_noise_rel(f, z, mag);
    res.resize(static_cast<std::size_t>(n));
    double ss = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      const cd zm = c.impedance(f[i]);
      res[static_cast<std::size_t>(i)] =
          mag ? cd(std::log(std::abs(zm) / std::abs(z[i])), 0.0) : (zm - z[i]) / std::abs(z[i]);
      ss += std::norm(res[static_cast<std::size_t>(i)]);
    }
    const double rms = std::sqrt(ss / (mag ? double(n) : 2.0 * double(n)));
    fit.residual_to_scatter = rms / fit.noise_scatter_rel;
    fit.residual_lag1 = lag1(res).rho;
  }

  // The fit as a whole.
  fit.status = "ok";
  fit.status_reasons.clear();
  auto inadequate = [&](const std::string& why) {
    fit.status = "inadequate";
    fit.status_reasons.push_back(why);
  };
  const double band_misfit = fit.misfit_abs_rel_rms;
  if (opt.data_checks && std::isfinite(band_misfit) && band_misfit > opt.max_band_misfit)
    inadequate("the network's |Z| misfit over the band is " + pct(band_misfit) + " (above " + pct(opt.max_band_misfit) +
               "): it does not describe these data");
  if (!fit.converged) inadequate("the least-squares fit did not converge");

  // Conditions that spoil every mode's figures.
  std::vector<std::string> every;
  if (fit.status != "ok") every.push_back("the fit is inadequate (" + fit.status_reasons.front() + ")");
  if (!(c.c0_f > 0)) every.push_back("C0 is not positive");
  if (c.tan_delta > opt.max_tan_delta)
    every.push_back("tan d " + fmt(c.tan_delta, 3) + " of C0 is outside [0, " + fmt(opt.max_tan_delta) + "]");
  for (const auto& b : c.branches)
    if (b.qm() < 1.0 && b.c_f > c.c0_f) {
      const std::string why = "C0 (" + fmt(c.c0_f) + " F) is absorbed into the low-Q branch at " + fmt(b.fs_hz()) +
                              " Hz (Q " + fmt(b.qm(), 2) + ", C1 " + fmt(b.c_f) + " F)";
      every.push_back(why);
      inadequate(why);
      break;
    }
  // C^T against the data's own low-frequency capacitance, when the data start
  // well below the first mode and the phase is trusted.
  if (opt.data_checks && !mag && !c.branches.empty() && f[0] < 0.5 * c.branches.front().fs_hz()) {
    const double w0 = kTwoPi * f[0];
    const double c_lf = (1.0 / z[0]).imag() / w0;
    const double c_net = (1.0 / c.impedance(f[0])).imag() / w0;
    if (c_lf > 0 && std::abs(c_net / c_lf - 1.0) > 0.1)
      every.push_back("the network's capacitance at " + fmt(f[0]) + " Hz (" + fmt(c_net) +
                      " F) differs from the data's (" + fmt(c_lf) + " F) by " + pct(std::abs(c_net / c_lf - 1.0)));
  }

  const double f_lo = f[0], f_hi = f[n - 1];
  for (std::size_t k = 0; k < fit.modes.size(); ++k) {
    auto& m = fit.modes[k];
    m.status = "ok";
    m.reasons.clear();
    m.sigma_notes.clear();
    for (const auto& why : every) add_reason(m, why);
    const double fs = m.fs_hz.value, fp = m.fp_hz.value;
    const double lo = std::max(std::isfinite(m.window_lo_hz) ? m.window_lo_hz : f_lo, f_lo);
    const double hi = std::min(std::isfinite(m.window_hi_hz) ? m.window_hi_hz : f_hi, f_hi);
    if (opt.data_checks && std::isfinite(m.misfit_rel_rms) && m.misfit_rel_rms > opt.max_window_misfit)
      add_reason(m, "misfit " + pct(m.misfit_rel_rms) + " in its window (above " + pct(opt.max_window_misfit) + ")");
    if (!(fs > f_lo && fs < f_hi)) add_reason(m, "fs " + fmt(fs, 6) + " Hz lies outside the data");
    if (std::isfinite(fp) && !(fp < f_hi)) add_reason(m, "fp " + fmt(fp, 6) + " Hz lies above the data (k_eff extrapolated)");
    const double q = m.qm_branch.value;
    const double bw = fs / q, step = grid_step_at(f, fs);
    if (opt.data_checks && std::isfinite(bw) && bw > hi - lo)
      add_reason(m, "half-power bandwidth " + fmt(bw) + " Hz (Q " + fmt(q, 3) + ") wider than its window (" +
                        fmt(hi - lo) + " Hz): the mode is not resolved");
    if (opt.data_checks && std::isfinite(bw) && bw < 2.0 * step)
      add_reason(m, "half-power bandwidth " + fmt(bw) + " Hz (Q " + fmt(q, 3) + ") narrower than two grid steps (" +
                        fmt(2 * step) + " Hz): Qm and R1 are not resolved");

    // Residual correlation in the window: σ × √((1 + ρ)/(1 − ρ)).
    if (opt.widen_sigma && opt.data_checks) {
      std::vector<cd> rw;
      for (Eigen::Index i = 0; i < n; ++i)
        if (f[i] >= lo && f[i] <= hi) rw.push_back(res[static_cast<std::size_t>(i)]);
      const auto l1 = lag1(rw);
      if (l1.points >= 8 && std::isfinite(l1.rho) && l1.rho * std::sqrt(double(l1.points)) > 3.0) {
        const double rho = std::min(l1.rho, 0.995);
        const double factor = std::sqrt((1 + rho) / (1 - rho));
        for (const auto& [name, x] : named_figures(m))
          if (std::isfinite(x->sigma)) x->sigma *= factor;
        m.sigma_notes.push_back("sigma x " + fmt(factor, 3) + ": the residual in the window is correlated (lag-1 " +
                                fmt(l1.rho, 3) + " over " + std::to_string(l1.points) +
                                " points, the effective-sample-size factor of an AR(1) residual)");
      }
    }

    // What the data show directly, against the network's figures.
    const double span = std::max(2.0 * bw, 3.0 * step);
    Eigen::VectorXd g(n), r(n), absz(n);
    if (opt.data_checks)
      for (Eigen::Index i = 0; i < n; ++i) {
        g[i] = mag ? 1.0 / std::abs(z[i]) : (1.0 / z[i]).real();
        r[i] = z[i].real();
        absz[i] = std::abs(z[i]);
      }
    double sys_fs = 0, sys_fp = 0, sys_fm = 0, sys_fn = 0;
    auto check = [&](Figure& x, const Eigen::VectorXd& y, double sign, const char* what, double& sys) {
      if (!std::isfinite(x.value)) return;
      const double a = std::max(lo, x.value - span), b = std::min(hi, x.value + span);
      const double fd = data_maximum(f, sign * y, a, b);
      if (!std::isfinite(fd)) {
        if (q >= 20) add_reason(m, std::string("no ") + what + " of the data near " + fmt(x.value, 6) + " Hz");
        return;
      }
      const double d = x.value - fd, st = grid_step_at(f, fd);
      const double s = std::isfinite(x.sigma) ? x.sigma : 0.0;
      if (std::abs(d) > 3.0 * s + 0.5 * st) {
        sys = std::abs(d);
        if (opt.widen_sigma) {
          widen(x, sys);
          m.sigma_notes.push_back(std::string("sigma includes ") + fmt(sys) + " Hz: the data's " + what + " is at " +
                                  fmt(fd, 7) + " Hz");
        } else if (q >= 20 && std::abs(d) > 3.0 * s + st) {
          add_reason(m, std::string("the data's ") + what + " is at " + fmt(fd, 7) + " Hz, " + fmt(std::abs(d) / std::max(s, 1e-300), 3) +
                            " sigma from " + fmt(x.value, 7) + " Hz");
        }
      }
    };
    if (opt.data_checks) {
      if (!mag) {
        check(m.fs_hz, g, 1.0, "conductance maximum", sys_fs);
        check(m.fp_hz, r, 1.0, "resistance maximum", sys_fp);
      }
      check(m.fm_hz, absz, -1.0, "|Z| minimum", sys_fm);
      check(m.fn_hz, absz, 1.0, "|Z| maximum", sys_fn);
    }
    if (mag) sys_fs = sys_fm, sys_fp = sys_fn;
    if (opt.widen_sigma) {
      widen(m.fr_hz, sys_fs > 0 ? sys_fs : sys_fm);
      widen(m.fa_hz, sys_fp > 0 ? sys_fp : sys_fn);
      if (mag) {
        widen(m.fs_hz, sys_fs);
        widen(m.fp_hz, sys_fp);
      }
      // k_eff carries its frequencies' systematic terms: k = √(1 − (a/b)²).
      auto widen_k = [&](Figure& k, double a, double b, double sa, double sb) {
        if (!(k.value > 0) || !(sa > 0 || sb > 0)) return;
        const double dka = -a / (b * b * k.value), dkb = a * a / (b * b * b * k.value);
        widen(k, std::hypot(dka * sa, dkb * sb));
      };
      widen_k(m.k_eff_ieee176, fs, fp, sys_fs, sys_fp);
      widen_k(m.k_eff_en50324, m.fm_hz.value, m.fn_hz.value, sys_fm, sys_fn);
    }

    // Plausibility.
    for (const Figure* k : {&m.k_eff_ieee176, &m.k_eff_en50324})
      if (std::isfinite(k->value) && k->value > opt.max_k_eff)
        add_reason(m, "k_eff " + fmt(k->value, 3) + " above " + fmt(opt.max_k_eff) +
                          " (beyond any material class: PZT ceramics reach about 0.75, relaxor single crystals 0.95)");
    {
      const auto& a = m.k_eff_ieee176;
      const auto& b = m.k_eff_en50324;
      // Both forms are the same network's; they agree only for a mode whose
      // figure of merit M = Qm·k² is large (IEEE 176: below M ≈ 20 the |Z|
      // extrema move off fs and fp by ~1/M, and the forms legitimately differ).
      const double merit = m.qm_branch.value * a.value * a.value;
      if (std::isfinite(a.value) && std::isfinite(b.value) && merit >= 20) {
        const double sab = std::hypot(std::isfinite(a.sigma) ? a.sigma : 0.0, std::isfinite(b.sigma) ? b.sigma : 0.0);
        const double d = std::abs(a.value - b.value);
        if (d > 3.0 * sab && d > opt.max_k_disagreement)
          add_reason(m, "k_eff forms disagree: " + fmt(a.value, 3) + " (IEEE 176, fs/fp) against " + fmt(b.value, 3) +
                            " (EN 50324-2, fm/fn)");
      }
    }
    for (const Figure* x : {&m.fs_hz, &m.fp_hz, &m.k_eff_ieee176})
      if (std::isfinite(x->value) && !std::isfinite(x->sigma)) {
        add_reason(m, "a sigma could not be determined (the fit's covariance is singular there)");
        break;
      }
  }

  // The data's conductance peaks of clear prominence: each a mode, or a note.
  fit.data_peaks.clear();
  if (!opt.data_checks) return;
  const auto peaks = prominent_conductance_peaks(f, z, mag, fit.noise_scatter_rel);
  for (const auto& p : peaks) {
    CircuitFit::DataPeak dp;
    dp.f_hz = p.f_hz;
    dp.prominence_s = p.prominence_s;
    const double tol = std::max(p.half_width_hz, 2.0 * grid_step(f, p.index));
    double best = tol;
    for (std::size_t k = 0; k < fit.modes.size(); ++k) {
      const double d = std::abs(fit.modes[k].fs_hz.value - p.f_hz);
      const double dm = std::isfinite(fit.modes[k].fm_hz.value) ? std::abs(fit.modes[k].fm_hz.value - p.f_hz) : d;
      if (std::min(d, dm) <= best) {
        best = std::min(d, dm);
        dp.mode = static_cast<int>(k);
      }
    }
    if (dp.mode < 0) {
      std::string why = static_cast<int>(c.branches.size()) >= opt.max_branches
                            ? "the fit holds " + std::to_string(opt.max_branches) + " branches at most (--modes)"
                            : "no branch there lowered the information criterion";
      fit.notes.push_back("the data's conductance peak at " + fmt(p.f_hz, 6) + " Hz (prominence " + fmt(p.prominence_s, 3) +
                          " S) has no mode: " + why);
    }
    fit.data_peaks.push_back(dp);
  }
  std::sort(fit.data_peaks.begin(), fit.data_peaks.end(), [](const auto& a, const auto& b) { return a.f_hz < b.f_hz; });
  // And the other way round: a mode the data show no clear peak for is the
  // network's, not a measurement.
  for (std::size_t k = 0; k < fit.modes.size(); ++k) {
    bool seen = false;
    for (const auto& p : fit.data_peaks) seen |= p.mode == static_cast<int>(k);
    if (!seen)
      add_reason(fit.modes[k], "the data show no conductance peak of clear prominence near fs " +
                                   fmt(fit.modes[k].fs_hz.value, 6) + " Hz (10 x the scatter noise, 1 % of the largest)");
  }
}

}  // namespace piezo::dsp
