#include "dsp/deskew.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "dsp/fft.hpp"

namespace piezo::dsp {

namespace {
constexpr double kTwoPi = 2.0 * std::numbers::pi;
using cd = std::complex<double>;
}  // namespace

double xcorr_delay(std::span<const double> v1, std::span<const double> v2, double fs,
                   double max_delay_s) {
  if (v1.size() != v2.size() || v1.size() < 16)
    throw std::invalid_argument("xcorr_delay: v1 and v2 need the same length, at least 16 samples");
  if (!(fs > 0) || !(max_delay_s > 0))
    throw std::invalid_argument("xcorr_delay: rate and max delay must be positive");
  const std::size_t n = v1.size();
  std::vector<double> d1(n), d2(n);
  for (std::size_t k = 1; k < n; ++k) {
    d1[k] = v1[k] - v1[k - 1];
    d2[k] = v2[k] - v2[k - 1];
  }
  const std::size_t nfft = good_fft_size(2 * n), up = 8;
  RealFft fwd(nfft);
  std::vector<cd> x1(fwd.bins()), x2(fwd.bins());
  fwd.forward(d1.data(), n, x1.data());
  fwd.forward(d2.data(), n, x2.data());
  RealFft inv(nfft * up);
  std::vector<cd> c(inv.bins(), cd(0.0));
  for (std::size_t k = 0; k < fwd.bins(); ++k) c[k] = std::conj(x1[k]) * x2[k];
  if (nfft % 2 == 0) c[nfft / 2] *= 0.5;  // the Nyquist bin is shared by ± frequencies
  std::vector<double> r(nfft * up);
  inv.inverse(c.data(), r.data(), r.size());
  // r[m] is the correlation at lag m/(up·fs); negative lags wrap to the end.
  const auto lag_max =
      static_cast<long>(std::min<double>(max_delay_s * fs * double(up), double(n * up / 2)));
  const long len = static_cast<long>(r.size());
  auto at = [&](long m) { return r[static_cast<std::size_t>((m % len + len) % len)]; };
  long best = 0;
  for (long m = -lag_max; m <= lag_max; ++m)
    if (at(m) > at(best)) best = m;
  const double ym = at(best - 1), y0 = at(best), yp = at(best + 1);
  const double den = ym - 2.0 * y0 + yp;
  const double frac = den < 0 ? 0.5 * (ym - yp) / den : 0.0;
  return (double(best) + frac) / (double(up) * fs);
}

std::vector<double> deskew_channel(std::span<const double> x, double fs, std::size_t jump_index,
                                   double delay_s) {
  const auto n = static_cast<long>(x.size());
  if (n < 4) throw std::invalid_argument("deskew_channel: need at least 4 samples");
  if (!(fs > 0) || !std::isfinite(delay_s))
    throw std::invalid_argument("deskew_channel: bad rate or delay");
  if (jump_index >= x.size())
    throw std::invalid_argument("deskew_channel: jump index beyond the record");
  const double d = delay_s * fs;
  const double jump = double(jump_index) + d;  // position of t = 0 in x
  // A sample closer to the jump than this (in samples: 5 ns at 10 MS/s, the
  // skew's own uncertainty) may have caught either side of it: left out.
  constexpr double eps = 0.05;
  // Samples strictly before / after the jump; a sample on it belongs to neither.
  const long pre_hi = std::min(n - 1, static_cast<long>(std::ceil(jump - eps)) - 1);
  const long post_lo = std::max(0L, static_cast<long>(std::floor(jump + eps)) + 1);
  std::vector<double> y(x.size());
  for (long m = 0; m < n; ++m) {
    const double q = double(m) + d;
    const bool post = m >= static_cast<long>(jump_index);
    long lo = post ? post_lo : 0, hi = post ? n - 1 : pre_hi;
    if (hi < lo) {  // nothing on this side (e.g. no pretrigger left): the other side's edge
      lo = post ? 0 : post_lo;
      hi = post ? pre_hi : n - 1;
    }
    const long pts = std::min(4L, hi - lo + 1);
    long k0 = static_cast<long>(std::floor(q)) - (pts - 1) / 2;
    k0 = std::clamp(k0, lo, hi - pts + 1);
    double v = 0;
    for (long a = 0; a < pts; ++a) {
      double w = 1;
      for (long b = 0; b < pts; ++b)
        if (b != a) w *= (q - double(k0 + b)) / double(a - b);
      v += w * x[static_cast<std::size_t>(k0 + a)];
    }
    y[static_cast<std::size_t>(m)] = v;
  }
  return y;
}

double phase_slope_delay(const Eigen::VectorXd& f, const Eigen::VectorXcd& t) {
  if (f.size() != t.size() || f.size() < 2)
    throw std::invalid_argument("phase_slope_delay: need >= 2 points of f and T");
  double num = 0, den = 0, prev = 0, unwrap = 0;
  for (Eigen::Index k = 0; k < f.size(); ++k) {
    double ph = std::arg(t[k]);
    if (k > 0) {
      double d = ph + unwrap - prev;
      while (d > std::numbers::pi) unwrap -= kTwoPi, d -= kTwoPi;
      while (d < -std::numbers::pi) unwrap += kTwoPi, d += kTwoPi;
    }
    ph += unwrap;
    prev = ph;
    const double w = kTwoPi * f[k], wt = std::abs(t[k]);
    num += wt * (-ph) * w;
    den += wt * w * w;
  }
  if (!(den > 0)) throw std::invalid_argument("phase_slope_delay: no frequency above 0");
  return num / den;
}

Eigen::VectorXcd divider_transfer(const Eigen::VectorXcd& z, double r1) {
  return z.array() / (z.array() + r1);
}

Eigen::VectorXcd divider_impedance(const Eigen::VectorXcd& t, double r1) {
  return r1 * t.array() / (1.0 - t.array());
}

Eigen::VectorXcd deskew_impedance(const Eigen::VectorXd& f, const Eigen::VectorXcd& z, double r1,
                                  double skew_s) {
  if (f.size() != z.size())
    throw std::invalid_argument("deskew_impedance: f and Z differ in length");
  if (!(r1 > 0)) throw std::invalid_argument("deskew_impedance: R1 must be positive");
  Eigen::VectorXcd t = divider_transfer(z, r1);
  for (Eigen::Index k = 0; k < f.size(); ++k) t[k] *= std::exp(cd(0.0, kTwoPi * f[k] * skew_s));
  return divider_impedance(t, r1);
}

void deskew_impedance(ImpedanceResult& r, double r1, double skew_s) {
  const Eigen::VectorXcd z0 = r.z_ohm;
  r.z_ohm = deskew_impedance(r.f_hz, z0, r1, skew_s);
  if (r.z_sigma_ohm.size() == r.f_hz.size()) {
    // First order: dZ'/dZ = R1²·e^{jωτ} / ((Z + R1)²·(1 − T')²).
    for (Eigen::Index k = 0; k < r.f_hz.size(); ++k) {
      const cd tp = r.z_ohm[k] / (r.z_ohm[k] + r1);
      const cd d = r1 * r1 / ((z0[k] + r1) * (z0[k] + r1) * (1.0 - tp) * (1.0 - tp));
      r.z_sigma_ohm[k] *= std::abs(d);
    }
  }
}

}  // namespace piezo::dsp
