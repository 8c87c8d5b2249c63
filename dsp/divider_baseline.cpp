#include "dsp/probability_text.hpp"
#include "dsp/divider_baseline.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include "dsp/fft.hpp"
#include "dsp/prony_ss.hpp"
#include "dsp/signal_stats.hpp"

namespace piezo::dsp {

namespace {

using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Harmonics of the hum the record holds: none below half a mains cycle (the
// hum is then inside the polynomial), else up to `max` below 1/10 of the band.
int hum_harmonics(double mains_hz, double seconds, int max) {
  if (!(mains_hz > 0) || seconds * mains_hz < 0.5) return 0;
  return max;
}

// The slow basis over the record (N samples at fs): Legendre P1..P_deg of
// u = 2t/T − 1 (column j − 1), then cos/sin of h·mains for h = 1..harmonics.
// No P0: a constant lives in the DFT's DC bin alone, which the fit leaves out
// (there a dielectric loss's long memory and the record's cut meet the
// offset); the offset is the pretrigger's. Evaluated a column at a time, so
// that memory stays that of one record whatever its length.
struct SlowBasis {
  std::size_t n = 0;
  double fs = 0;
  int deg = 0, harmonics = 0;
  double mains_hz = 0;
  Eigen::Index cols() const { return deg + 2 * harmonics; }
  double at(Eigen::Index j, std::size_t i) const {
    const double t = double(i) / fs;
    if (j < deg) {  // P_{j+1}: (m)P_m = (2m − 1)u P_{m−1} − (m − 1)P_{m−2}
      const double u = 2.0 * t / (double(n) / fs) - 1.0;
      double p0 = 1.0, p1 = u;
      for (int m = 2; m <= j + 1; ++m) {
        const double p2 = ((2.0 * m - 1.0) * u * p1 - (m - 1.0) * p0) / m;
        p0 = p1;
        p1 = p2;
      }
      return p1;
    }
    const int h = static_cast<int>(j - deg) / 2 + 1;
    const double ph = kTwoPi * h * mains_hz * t;
    return (j - deg) % 2 == 0 ? std::cos(ph) : std::sin(ph);
  }
  // Its first `bins` DFT bins (scaled by Δt, as the channels').
  Eigen::VectorXcd dft(Eigen::Index j, Eigen::Index bins) const {
    Eigen::VectorXd col(static_cast<Eigen::Index>(n));
    for (std::size_t i = 0; i < n; ++i) col[static_cast<Eigen::Index>(i)] = at(j, i);
    return (rfft(col, n) / fs).head(bins);
  }
};

struct Fit {
  double chi2 = 0;
  int rows = 0;
  Eigen::VectorXd coef;  // in the columns' own units
  Eigen::VectorXd sigma;
  bool ok = false;
};

// Weighted real least squares on the stacked Re/Im rows of complex columns
// (bins 1..K−1; the DC bin left out). Columns scaled to unit norm for the solve.
Fit solve(const std::vector<Eigen::VectorXcd>& cols, const Eigen::VectorXcd& y, const Eigen::VectorXd& w) {
  Fit f;
  const Eigen::Index K = y.size(), p = static_cast<Eigen::Index>(cols.size());
  const Eigen::Index rows = 2 * (K - 1);
  Eigen::MatrixXd a(rows, p);
  Eigen::VectorXd b(rows);
  auto fill = [&](Eigen::Index c, const Eigen::VectorXcd& v, Eigen::VectorXd* out) {
    Eigen::Index r = 0;
    for (Eigen::Index k = 1; k < K; ++k) {
      const double wk = w[k] * std::sqrt(2.0);  // Re, Im each half the bin's variance
      (out ? (*out)[r] : a(r, c)) = v[k].real() * wk;
      ++r;
      (out ? (*out)[r] : a(r, c)) = v[k].imag() * wk;
      ++r;
    }
  };
  for (Eigen::Index c = 0; c < p; ++c) fill(c, cols[static_cast<std::size_t>(c)], nullptr);
  fill(0, y, &b);
  Eigen::VectorXd scale(p);
  for (Eigen::Index c = 0; c < p; ++c) {
    scale[c] = a.col(c).norm();
    if (!(scale[c] > 0) || !std::isfinite(scale[c])) return f;
    a.col(c) /= scale[c];
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = svd.singularValues();
  if (!(sv[p - 1] > 1e-12 * sv[0])) return f;
  const Eigen::VectorXd x = svd.solve(b);
  f.chi2 = (a * x - b).squaredNorm();
  f.rows = static_cast<int>(rows);
  const Eigen::MatrixXd vs = svd.matrixV() * sv.cwiseInverse().asDiagonal();
  f.coef = x.cwiseQuotient(scale);
  f.sigma = vs.rowwise().norm().cwiseQuotient(scale);
  f.ok = true;
  return f;
}

}  // namespace

double DividerBaseline::excess_noise(double f_hz) const {
  if (!tested || nu < 1 || !(chi2_per_dof > 1.0 + 4.0 * std::sqrt(2.0 / nu)) || !(band_hz > 0)) return 1.0;
  return f_hz <= band_hz ? chi2_per_dof : 1.0 + (chi2_per_dof - 1.0) * band_hz / f_hz;
}

DividerBaseline estimate_divider_baseline(const DividerRecord& rec, const DividerBaselineOptions& opt) {
  DividerBaseline out;
  const std::size_t n = rec.v1.size(), n0 = rec.pretrigger_samples;
  const double fs = rec.sample_rate_hz, r1 = rec.r1_ohm;
  if (rec.v2.size() != n || n0 >= n || !(fs > 0) || !(r1 > 0)) {
    out.note = "not a usable divider record";
    return out;
  }
  const std::size_t N = n - n0;
  if (N < 256) {
    out.note = "too short for a baseline test (" + std::to_string(N) + " samples after t = 0)";
    return out;
  }
  const double dt = 1.0 / fs, T = double(N) * dt;
  double m1 = 0, m2 = 0;
  if (n0 >= 16) {
    for (std::size_t i = 0; i < n0; ++i) {
      m1 += rec.v1[i];
      m2 += rec.v2[i];
    }
    m1 /= double(n0);
    m2 /= double(n0);
  }
  Eigen::VectorXd x1(static_cast<Eigen::Index>(N)), x2(static_cast<Eigen::Index>(N));
  for (std::size_t i = 0; i < N; ++i) {
    x1[static_cast<Eigen::Index>(i)] = rec.v1[n0 + i] - m1;
    x2[static_cast<Eigen::Index>(i)] = rec.v2[n0 + i] - m2;
    if (!std::isfinite(x1[static_cast<Eigen::Index>(i)]) || !std::isfinite(x2[static_cast<Eigen::Index>(i)])) {
      out.note = "non-finite samples";
      return out;
    }
  }
  const double s1 = estimate_noise_std(x1), s2 = estimate_noise_std(x2);
  if (!(s1 > 0) || !(s2 > 0)) {
    out.note = "no noise to weigh the test by (a channel without white noise)";
    return out;
  }
  const Eigen::VectorXcd X1 = rfft(x1, N) * dt, X2 = rfft(x2, N) * dt;
  std::vector<double> tried = opt.mains_hz > 0 ? std::vector<double>{opt.mains_hz} : std::vector<double>{50.0, 60.0};
  // The band: `cycles` cycles of the record, halved while a resonance shows in it.
  double fc = opt.cycles / T;
  Eigen::Index K = 0;
  std::vector<Eigen::VectorXcd> model_cols;
  Eigen::VectorXd w;
  Eigen::VectorXcd y;
  // R1·(jω)^m·X2 for m = 0..4 (the admittance's loss, capacitance, the modes'
  // tail; the even powers take a channel skew and the sampled record's
  // derivative, (1 − e^{−jωΔt})/Δt ≈ jω(1 − jωΔt/2)); a dielectric loss:
  // R1·ω·X2 (ωC·tanδ) and R1·jω·ln(ω/ω₁)·X2 (a constant-phase permittivity
  // falling with frequency, to first order) — the refsim corpus's dielectric-
  // loss cases read as a baseline without them; the boundary terms (jω)^m,
  // m = 0..3, and for the band's test R1·(jω)⁵·X2 last.
  constexpr int kPowers = 5, kY = kPowers + 2, kBoundary = 4;
  auto base_columns = [&](Eigen::Index k_max, bool fifth) {
    std::vector<Eigen::VectorXcd> c(kY + kBoundary + (fifth ? 1 : 0), Eigen::VectorXcd(k_max));
    for (Eigen::Index k = 0; k < k_max; ++k) {
      const double om = kTwoPi * double(k) / T;
      const cd jw(0.0, om);
      cd p = 1.0;
      for (int m = 0; m < kPowers; ++m, p *= jw) c[static_cast<std::size_t>(m)][k] = r1 * p * X2[k];
      c[kPowers][k] = r1 * om * X2[k];
      c[kPowers + 1][k] = k == 0 ? cd(0.0) : r1 * jw * std::log(double(k)) * X2[k];
      p = 1.0;
      for (int m = 0; m < kBoundary; ++m, p *= jw) c[static_cast<std::size_t>(kY + m)][k] = p;
      if (fifth) c[kY + kBoundary][k] = r1 * std::pow(jw, 5) * X2[k];
    }
    return c;
  };
  const SlowBasis full_basis{N, fs, opt.poly_degree, hum_harmonics(tried.front(), T, opt.harmonics), tried.front()};
  for (;;) {
    K = static_cast<Eigen::Index>(std::floor(fc * T)) + 1;  // bins 0 .. fc
    const Eigen::Index p_max = kY + kBoundary + 1 + full_basis.cols();
    if (2 * (K - 1) < p_max + 10 || fc < opt.min_cycles / T) {
      out.note = "the record's lowest bins cannot hold the baseline test (" + std::to_string(K) + " bins up to " +
                 std::to_string(static_cast<long>(fc)) + " Hz)";
      return out;
    }
    y = X1.head(K) - X2.head(K);
    {  // The capacitive region: Im Y/ω (Y = (X1 − X2)/(R1·X2)) of the band's top
       // quarter within 10 % of its bottom quarter's (medians: robust to the
       // noise of single bins); a resonance inside the band moves it by far more.
      std::vector<double> lo, hi;
      for (Eigen::Index k = 1; k < K; ++k) {
        const double om = kTwoPi * double(k) / T;
        const double c = (y[k] / (r1 * X2[k])).imag() / om;
        if (k <= (K - 1) / 4)
          lo.push_back(c);
        else if (k > 3 * (K - 1) / 4)
          hi.push_back(c);
      }
      auto median = [](std::vector<double> v) {
        std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
        return v[v.size() / 2];
      };
      if (!lo.empty() && !hi.empty()) {
        const double ml = median(lo), mh = median(hi);
        if (!(ml > 0) || !(std::abs(mh / ml - 1.0) < 0.1)) {
          fc *= 0.5;
          continue;
        }
      }
    }
    // Weights: each bin's white noise, n1 − (1 + R1·Y)·n2, with Y from an
    // unweighted first pass.
    w = Eigen::VectorXd::Ones(K);
    auto c5 = base_columns(K, true);
    for (Eigen::Index j = 0; j < full_basis.cols(); ++j) c5.push_back(full_basis.dft(j, K));
    Fit f0 = solve(c5, y, w);
    if (!f0.ok) {
      out.note = "the baseline test's least squares is singular";
      return out;
    }
    for (Eigen::Index k = 0; k < K; ++k) {
      const cd jw(0.0, kTwoPi * double(k) / T);
      cd ry = 0.0, p = 1.0;
      for (int m = 0; m < kPowers; ++m, p *= jw) ry += r1 * p * f0.coef[m];
      ry += r1 * (jw.imag() * f0.coef[kPowers] + (k == 0 ? cd(0.0) : jw * std::log(double(k)) * f0.coef[kPowers + 1]));
      ry += r1 * std::pow(jw, 5) * f0.coef[kY + kBoundary];
      const double var = double(N) * dt * dt * (s1 * s1 + std::norm(1.0 + ry) * s2 * s2);
      w[k] = 1.0 / std::sqrt(var);
    }
    const Fit f5 = solve(c5, y, w);
    constexpr int k5 = kY + kBoundary;
    // Against the residual's own scale (1/f noise raises it at these bins).
    const double birge = f5.ok ? std::sqrt(std::max(1.0, f5.chi2 / std::max<double>(1, f5.rows - double(c5.size())))) : 1;
    if (f5.ok && std::abs(f5.coef[k5]) > 5.0 * birge * f5.sigma[k5]) {  // a resonance inside the band
      fc *= 0.5;
      continue;
    }
    model_cols = base_columns(K, false);
    break;
  }
  out.band_hz = double(K - 1) / T;
  const Fit f_off = solve(model_cols, y, w);
  if (!f_off.ok) {
    out.note = "the baseline test's least squares is singular";
    return out;
  }
  out.tested = true;
  Fit best;
  SlowBasis best_basis;
  double best_delta = -1, best_logp = 0;
  for (double mains : tried) {
    const int h = hum_harmonics(mains, T, opt.harmonics);
    const SlowBasis basis{N, fs, opt.poly_degree, h, mains};
    std::vector<Eigen::VectorXcd> cols = model_cols;
    for (Eigen::Index j = 0; j < basis.cols(); ++j) cols.push_back(basis.dft(j, K));
    const Fit f = solve(cols, y, w);
    if (!f.ok) continue;
    const int dof = static_cast<int>(basis.cols());
    const int nu = f.rows - static_cast<int>(cols.size());
    // Δχ² against the residual's own scale when above the white noise (1/f
    // noise, a misfit): an F-like test that a wrong noise level cannot pass.
    const double scale = std::max(1.0, f.chi2 / std::max(1, nu));
    const double delta = std::max(0.0, f_off.chi2 - f.chi2) / scale;
    const double logp = std::min(0.0, log_gamma_tail((dof + 1) / 2, 0.5 * delta) + std::log(double(tried.size())));
    if (delta > best_delta) {
      best_delta = delta;
      best_logp = logp;
      best = f;
      best_basis = basis;
      out.dof = dof;
      out.mains_hz = h > 0 ? mains : 0;
      out.chi2_per_dof = f.chi2 / std::max(1, nu);
      out.nu = nu;
    }
  }
  if (!best.ok) {
    out.tested = false;
    out.note = "the baseline test's least squares is singular";
    return out;
  }
  out.delta_chi2 = best_delta;
  out.log10_p = best_logp / std::log(10.0);
  out.found = best_logp < std::log(opt.p_value);
  const Eigen::VectorXd c = best.coef.tail(best_basis.cols());
  Eigen::VectorXd d = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(N));
  for (std::size_t i = 0; i < N; ++i)
    for (Eigen::Index j = 0; j < c.size(); ++j) d[static_cast<Eigen::Index>(i)] += c[j] * best_basis.at(j, i);
  out.samples.assign(d.data(), d.data() + d.size());
  out.rms_v = std::sqrt(d.squaredNorm() / double(d.size()));
  out.offset_v = d.mean();
  out.slope_v_per_s = opt.poly_degree >= 1 ? c[0] * 2.0 / T : 0.0;
  {
    const int nu = best.rows - static_cast<int>(best.coef.size());
    const double birge = std::sqrt(std::max(1.0, best.chi2 / std::max(1, nu)));
    const Eigen::VectorXd sc = best.sigma.tail(best_basis.cols()) * birge;
    out.slope_sigma_v_per_s = opt.poly_degree >= 1 ? sc[0] * 2.0 / T : kNaN;
  }
  const int deg = opt.poly_degree;
  if (out.mains_hz > 0) out.hum_v = std::hypot(c[deg], c[deg + 1]);
  char buf[240];
  std::snprintf(buf, sizeof buf,
                "channel 1 - channel 2 baseline %s: rms %.3g V (mean %.3g V, slope %.3g V/s%s), delta chi2 %.1f on "
                "%d dof (chance %s) in the bins up to %.0f Hz",
                out.found ? "found" : "not significant", out.rms_v, out.offset_v, out.slope_v_per_s,
                out.mains_hz > 0 ? (", " + std::to_string(static_cast<int>(out.mains_hz)) + " Hz hum").c_str() : "",
                out.delta_chi2, out.dof, probability_text(out.log10_p).c_str(), out.band_hz);
  out.note = buf;
  if (!out.found) out.samples.clear();
  return out;
}

}  // namespace piezo::dsp
