#include "update/residual_regions.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace piezo::update {

namespace {

using cd = std::complex<double>;
constexpr double kTwoPi = 6.283185307179586;
constexpr int kMaxWindow = 64;    // bins, as the fit's band test
constexpr int kMaxRegion = 512;   // bins a region may grow to
constexpr double kExplained = 0.5;
constexpr double kGrowZ = 2.5;  // z of a bin a region grows into (noise: chance 8 %)  // share of a region's excess a shape must remove to name it

// Weighted least squares of e on real multiples of the columns −L·V1·g_c
// over bins `idx`: returns the χ² it removes (2 per bin: re and im, each of
// variance var/2) and the coefficients.
struct ShapeFit {
  Eigen::VectorXd a;
  double delta_chi2 = 0;
};
ShapeFit fit_shapes(const ResidualSpectrum& s, std::size_t lo, std::size_t hi,
                    const std::vector<std::vector<cd>>& g) {
  const auto m = static_cast<Eigen::Index>(hi - lo);
  const auto p = static_cast<Eigen::Index>(g.size());
  Eigen::MatrixXd a(2 * m, p);
  Eigen::VectorXd b(2 * m);
  for (Eigen::Index i = 0; i < m; ++i) {
    const std::size_t k = lo + static_cast<std::size_t>(i);
    const double w = std::sqrt(2.0 / s.var[k]);
    b[2 * i] = w * s.e[k].real();
    b[2 * i + 1] = w * s.e[k].imag();
    for (Eigen::Index c = 0; c < p; ++c) {
      const cd col = -s.lv1[k] * g[static_cast<std::size_t>(c)][static_cast<std::size_t>(i)];
      a(2 * i, c) = w * col.real();
      a(2 * i + 1, c) = w * col.imag();
    }
  }
  ShapeFit out;
  out.a = a.colPivHouseholderQr().solve(b);
  if (!out.a.allFinite()) {
    out.a = Eigen::VectorXd::Zero(p);
    return out;
  }
  out.delta_chi2 = b.squaredNorm() - (b - a * out.a).squaredNorm();
  return out;
}

// The branch's δY per unit C_b: jω / (1 − ω²/ω_b² + jω/(ω_b·Q)).
cd branch(double omega, double omega_b, double q) {
  const double u = omega / omega_b;
  return cd(0.0, omega) / cd(1.0 - u * u, u / q);
}

// Best C_b ≥ 0 for (f_b, Q) over [lo, hi): the χ² it removes.
double resonance_drop(const ResidualSpectrum& s, std::size_t lo, std::size_t hi, double f_b, double q,
                      double* c_b = nullptr) {
  double num = 0, den = 0;
  const double wb = kTwoPi * f_b;
  for (std::size_t k = lo; k < hi; ++k) {
    const cd col = -s.lv1[k] * s.dt_dy[k] * branch(kTwoPi * s.f_hz[k], wb, q);
    const double w = 2.0 / s.var[k];
    num += w * (std::conj(col) * s.e[k]).real();
    den += w * std::norm(col);
  }
  const double c = den > 0 ? std::max(0.0, num / den) : 0.0;
  if (c_b) *c_b = c;
  return c * c * den;  // = num²/den when c > 0
}

std::string khz(double f) {
  char b[32];
  std::snprintf(b, sizeof b, f >= 100e3 ? "%.1f" : "%.2f", f / 1e3);
  return b;
}

}  // namespace

std::vector<ResidualRegion> residual_regions(const ResidualSpectrum& s, int max_regions, double p_threshold) {
  std::vector<ResidualRegion> out;
  const std::size_t n = s.size();
  if (n < 16 || max_regions < 1) return out;
  // z = |e|²/var, scaled by its median to ln 2 (the median of an Exp(1)).
  std::vector<double> z(n);
  for (std::size_t k = 0; k < n; ++k) z[k] = s.var[k] > 0 ? std::norm(s.e[k]) / s.var[k] : 0.0;
  std::vector<double> sorted = z;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(n / 2), sorted.end());
  const double med = sorted[n / 2];
  const double scale = med > 0 ? std::log(2.0) / med : 1.0;
  for (auto& v : z) v *= scale;
  std::vector<double> cum(n + 1, 0.0);
  for (std::size_t k = 0; k < n; ++k) cum[k + 1] = cum[k] + z[k];
  auto sum = [&](std::size_t a, std::size_t b) { return cum[b] - cum[a]; };  // [a, b)
  double windows = 0;  // how many the band test's scan tries (Bonferroni)
  for (int w = 1; w <= kMaxWindow && static_cast<std::size_t>(w) <= n; w *= 2)
    windows += double((n - static_cast<std::size_t>(w)) / static_cast<std::size_t>(std::max(1, w / 2)) + 1);
  const double total_excess = std::max(1e-300, 2.0 * (cum[n] - double(n)));
  std::vector<bool> used(n, false);
  for (int r = 0; r < max_regions; ++r) {
    // The least likely window among the bins not yet taken.
    double best = 0;
    std::size_t b0 = 0, b1 = 0;
    for (int w = 1; w <= kMaxWindow && static_cast<std::size_t>(w) <= n; w *= 2) {
      const std::size_t step = static_cast<std::size_t>(std::max(1, w / 2));
      for (std::size_t a = 0; a + static_cast<std::size_t>(w) <= n; a += step) {
        const std::size_t b = a + static_cast<std::size_t>(w);
        if (std::any_of(used.begin() + static_cast<long>(a), used.begin() + static_cast<long>(b), [](bool u) { return u; }))
          continue;
        const double lq = log_gamma_tail(w, sum(a, b));
        if (lq < best) best = lq, b0 = a, b1 = b;
      }
    }
    const double log10_p = std::min(0.0, (best + std::log(windows)) / std::log(10.0));
    if (b1 == 0 || !(log10_p < std::log10(p_threshold))) break;
    // Trim its edges to bins that stand out (z ≥ kGrowZ; the window sizes
    // double, so the least likely one may hold noise bins beside the
    // misfit) …
    // (an edge bin that stands out alone, its two inner neighbours not, is
    // a noise outlier: trimmed too) …
    auto trims = [&](std::size_t k, std::size_t in1, std::size_t in2) {
      return z[k] < kGrowZ || (z[in1] < kGrowZ && z[in2] < kGrowZ);
    };
    while (b1 - b0 > 3 && trims(b0, b0 + 1, b0 + 2)) ++b0;
    while (b1 - b0 > 3 && trims(b1 - 1, b1 - 2, b1 - 3)) --b1;
    while (b1 - b0 > 1 && z[b0] < kGrowZ) ++b0;
    while (b1 - b0 > 1 && z[b1 - 1] < kGrowZ) --b1;
    // … and grow it a bin at a time into bins that stand out (a resonance's
    // skirts, the rest of a broad misfit), across a single dip where the bin
    // after it stands out too; the side that stands out more first.
    auto grows = [&](std::size_t k, std::size_t k2) {  // k next, k2 after it (n: none)
      if (used[k]) return -1.0;
      if (z[k] >= kGrowZ) return z[k];
      if (k2 < n && !used[k2] && z[k2] >= kGrowZ && 0.5 * (z[k] + z[k2]) >= kGrowZ) return 0.5 * (z[k] + z[k2]);
      return -1.0;
    };
    while (b1 - b0 < static_cast<std::size_t>(kMaxRegion)) {
      const double l = b0 > 0 ? grows(b0 - 1, b0 >= 2 ? b0 - 2 : n) : -1.0;
      const double h = b1 < n ? grows(b1, b1 + 1) : -1.0;
      if (l < 0 && h < 0) break;
      if (l >= h) --b0;
      else ++b1;
    }
    ResidualRegion g;
    g.f_lo_hz = s.f_hz[b0];
    g.f_hi_hz = s.f_hz[b1 - 1];
    g.bins = static_cast<int>(b1 - b0);
    g.log10_p = log10_p;
    g.excess = sum(b0, b1) / double(b1 - b0);
    // The shapes on the region as grown (it took a resonance's skirts as
    // long as they stood above the noise).
    const std::size_t lo = b0, hi = b1;
    const std::size_t m = hi - lo;
    double chi2 = 0;
    for (std::size_t k = lo; k < hi; ++k) chi2 += 2.0 * std::norm(s.e[k]) / s.var[k];
    g.chi2 = chi2;
    const double region_excess = std::max(0.0, chi2 - 2.0 * double(m));
    g.share = std::min(1.0, std::max(0.0, 2.0 * (sum(b0, b1) - double(b1 - b0)) / total_excess));
    std::vector<cd> level(m), phase(m), slope(m);
    for (std::size_t i = 0; i < m; ++i) {
      const std::size_t k = lo + i;
      level[i] = s.t[k];
      phase[i] = cd(0.0, 1.0) * s.t[k];
      slope[i] = cd(0.0, -kTwoPi * s.f_hz[k]) * s.t[k];
    }
    const ShapeFit lp = fit_shapes(s, lo, hi, {level, phase});
    const ShapeFit sl = fit_shapes(s, lo, hi, {slope});
    g.level_pct = 100.0 * lp.a[0];
    g.phase_deg = lp.a[1] * 180.0 / M_PI;
    g.delay_s = sl.a[0];
    // The extra resonance: a grid over the region's bins and Q, then a
    // pattern search on (ln f_b, ln Q).
    double rd = 0, f_best = 0, q_best = 0;
    for (std::size_t k = b0; k < b1; ++k)
      for (double q = 2.0; q <= 5000.0; q *= 1.5) {
        const double d = resonance_drop(s, lo, hi, s.f_hz[k], q);
        if (d > rd) rd = d, f_best = s.f_hz[k], q_best = q;
      }
    if (rd > 0) {
      double df = 0.5 * (s.f_hz[std::min(n - 1, b0 + 1)] - s.f_hz[b0]) / f_best, dq = 0.2;
      for (int it = 0; it < 40 && (df > 1e-7 || dq > 1e-4); ++it) {
        bool moved = false;
        for (const auto& [a, b] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
          const double f = f_best * std::exp(a * df), q = std::clamp(q_best * std::exp(b * dq), 1.0, 1e5);
          const double d = resonance_drop(s, lo, hi, f, q);
          if (d > rd) rd = d, f_best = f, q_best = q, moved = true;
        }
        if (!moved) df *= 0.5, dq *= 0.5;
      }
    }
    // Akaike: each fitted number costs 2 of χ².
    const double score_lp = lp.delta_chi2 - 4.0, score_sl = sl.delta_chi2 - 2.0, score_rs = rd - 6.0;
    const double top = std::max({score_lp, score_sl, score_rs});
    const double drop = top == score_rs ? rd : top == score_lp ? lp.delta_chi2 : sl.delta_chi2;
    char buf[200];
    if (top <= 0 || drop < kExplained * region_excess) {
      g.kind = "broadband";
      std::snprintf(buf, sizeof buf, "a misfit of no simple shape (residual %.3g times the noise)", g.excess);
    } else if (top == score_rs) {
      ExtraResonance x;
      x.f_hz = f_best;
      x.q = q_best;
      resonance_drop(s, lo, hi, f_best, q_best, &x.c_f);
      x.delta_chi2 = rd;
      // The transducer's capacitance there: Im Y/ω of the model at the bin nearest f_b.
      std::size_t kb = lo;
      for (std::size_t k = lo; k < hi; ++k)
        if (std::abs(s.f_hz[k] - f_best) < std::abs(s.f_hz[kb] - f_best)) kb = k;
      const double c_t = s.y_tube[kb].imag() / (kTwoPi * s.f_hz[kb]);
      x.k_eff = c_t > 0 ? std::sqrt(x.c_f / (x.c_f + c_t)) : NAN;
      // The record's resolution: the median bin spacing.
      std::vector<double> df;
      for (std::size_t k = 1; k < n; ++k) df.push_back(s.f_hz[k] - s.f_hz[k - 1]);
      std::nth_element(df.begin(), df.begin() + static_cast<long>(df.size() / 2), df.end());
      const double bin = df[df.size() / 2];
      x.q_resolved = x.f_hz / x.q >= 3.0 * bin;
      x.q_min = x.f_hz / (3.0 * bin);
      g.kind = "extra resonance";
      g.resonance = x;
      char qtext[64];
      if (x.q_resolved) std::snprintf(qtext, sizeof qtext, "Q %.3g", x.q);
      else std::snprintf(qtext, sizeof qtext, "Q above %.2g, narrower than the record resolves", x.q_min);
      std::snprintf(buf, sizeof buf, "an extra resonance at %s kHz (%s, k_eff %.2g)", khz(x.f_hz).c_str(), qtext,
                    x.k_eff);
    } else if (top == score_sl) {
      g.kind = "phase slope";
      std::snprintf(buf, sizeof buf, "a phase slope (a delay of %.3g ns)", g.delay_s * 1e9);
    } else if (std::abs(lp.a[0]) >= std::abs(lp.a[1])) {
      g.kind = "level";
      std::snprintf(buf, sizeof buf, "a level offset of %+.3g %%", g.level_pct);
    } else {
      g.kind = "phase";
      std::snprintf(buf, sizeof buf, "a phase offset of %+.3g deg", g.phase_deg);
    }
    g.description = khz(g.f_lo_hz) + "-" + khz(g.f_hi_hz) + " kHz: " + buf;
    out.push_back(g);
    // The next region is disjoint from this one and its skirts (half its width each side).
    const std::size_t pad = std::max<std::size_t>(4, m / 2);
    for (std::size_t k = lo > pad ? lo - pad : 0; k < std::min(n, hi + pad); ++k) used[k] = true;
  }
  return out;
}

}  // namespace piezo::update
