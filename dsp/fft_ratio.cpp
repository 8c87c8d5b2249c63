#include "dsp/fft_ratio.hpp"

#include <Eigen/Cholesky>

#include <cmath>
#include <stdexcept>

#include "dsp/fft.hpp"
#include "dsp/prony_ss.hpp"  // estimate_noise_std

namespace piezo::dsp {

ImpedanceResult impedance_fft(const DividerRecord& rec, const FftRatioOptions& opt) {
  DividerSignals s = prepare_divider(rec, "impedance_fft", opt.prep);
  // Channel noise is white on the recorded samples: measure it before the
  // first difference (its gain per bin below).
  const double n1 = estimate_noise_std(s.v1), n2 = estimate_noise_std(s.v2);
  if (opt.one_sided) {
    s.v1[0] *= 0.5;
    s.v2[0] *= 0.5;
    s.i[0] *= 0.5;
  }
  const Eigen::Index n = s.size();
  // The last sample from a quadratic fit to the last M (end_fit_samples):
  // x̂ = Σ h_j x_j over the tail, h the fit's weights for its value at the end.
  const Eigen::Index tail = opt.difference ? std::min<Eigen::Index>(
                                                 static_cast<Eigen::Index>(opt.end_fit_samples), n / 2)
                                           : 0;
  Eigen::VectorXd h;
  if (tail >= 3) {
    Eigen::MatrixXd t(tail, 3);
    for (Eigen::Index j = 0; j < tail; ++j) {
      const double u = double(j - (tail - 1)) / double(tail);  // 0 at the last sample
      t(j, 0) = 1.0;
      t(j, 1) = u;
      t(j, 2) = u * u;
    }
    // h = T (TᵀT)^{-1} e_0: the fitted polynomial's constant term at u = 0.
    const Eigen::Vector3d e0(1.0, 0.0, 0.0);
    h = t * (t.transpose() * t).ldlt().solve(e0);
    for (Eigen::VectorXd* v : {&s.v1, &s.v2, &s.i}) (*v)[n - 1] = v->tail(tail).dot(h);
  }
  if (opt.difference) difference_in_place(s);
  const std::size_t nfft = opt.nfft ? opt.nfft : static_cast<std::size_t>(n);
  if (nfft < static_cast<std::size_t>(n))
    throw std::invalid_argument("impedance_fft: nfft shorter than the record");
  const Eigen::VectorXd w = make_window(opt.window, n);
  const Eigen::VectorXcd X1 = rfft(s.v1.cwiseProduct(w), nfft);
  const Eigen::VectorXcd X2 = rfft(s.v2.cwiseProduct(w), nfft);
  // White noise σ on a channel: with x_k scaled by b_k (½ at k = 0 when
  // one-sided), differenced (d_k = b_k x_k − b_{k−1} x_{k−1}) and windowed, the
  // noise of sample j enters bin θ = 2πk/nfft as b_j n_j (w_j − w_{j+1}e^{−jθ})
  // (w_n = 0), so E|δX|² = σ²·(A + B − 2C·cos θ), A = Σ b_j²w_j²,
  // B = Σ b_j²w_{j+1}², C = Σ b_j²w_j w_{j+1}; σ²·A without the difference.
  // The B term is the last sample's noise, which the difference leaves whole in
  // every bin: it, not |1 − e^{−jθ}|²·σ²·Σw², sets the noise of the lowest bins
  // (below about fs/(2π·√n): 11 kHz for 20 000 samples at 10 MS/s).
  double sa = 0, sb = 0, sc = 0;
  for (Eigen::Index j = 0; j < n; ++j) {
    const double b2 = (opt.one_sided && j == 0) ? 0.25 : 1.0;
    const double wj = w[j], wn1 = j + 1 < n ? w[j + 1] : 0.0;
    sa += b2 * wj * wj;
    sb += b2 * wn1 * wn1;
    sc += b2 * wj * wn1;
  }
  const double df = s.sample_rate_hz / double(nfft);
  const double fmax = opt.fmax_hz > 0 ? opt.fmax_hz : s.sample_rate_hz / 2;
  ImpedanceResult r;
  r.method = "fft";
  r.samples_used = static_cast<std::size_t>(n);
  std::vector<Eigen::Index> keep;
  for (Eigen::Index k = 1; k < X1.size(); ++k) {  // no DC: Z of a capacitor is infinite there
    const double f = df * double(k);
    if (f >= opt.fmin_hz && f <= fmax) keep.push_back(k);
  }
  if (keep.size() < 2) throw std::invalid_argument("impedance_fft: fewer than 2 bins in [fmin, fmax]");
  const auto m = static_cast<Eigen::Index>(keep.size());
  r.f_hz.resize(m);
  r.z_ohm.resize(m);
  r.z_sigma_ohm.resize(m);
  for (Eigen::Index q = 0; q < m; ++q) {
    const Eigen::Index k = keep[static_cast<std::size_t>(q)];
    const std::complex<double> d = X1[k] - X2[k];
    r.f_hz[q] = df * double(k);
    r.z_ohm[q] = s.r1_ohm * X2[k] / d;
    // ∂Z/∂X1 = −Z/d, ∂Z/∂X2 = R1·X1/d²
    const double g1 = std::abs(r.z_ohm[q] / d), g2 = std::abs(s.r1_ohm * X1[k] / (d * d));
    const double th = 2.0 * M_PI * double(k) / double(nfft);
    double gain2 = opt.difference ? sa + sb - 2.0 * sc * std::cos(th) : sa;
    if (h.size()) {
      // Over the tail the noise of sample j enters as c_j + h_j·c_{n−1}
      // instead of c_j (c_j = b_j(w_j e^{−jθj} − w_{j+1} e^{−jθ(j+1)}), c_{n−1}
      // without its own term): swap the tail's share of the sum.
      auto c = [&](Eigen::Index j) {
        const std::complex<double> a = w[j] * std::exp(std::complex<double>(0, -th * double(j)));
        const std::complex<double> b =
            j + 1 < n ? w[j + 1] * std::exp(std::complex<double>(0, -th * double(j + 1))) : 0.0;
        return ((opt.one_sided && j == 0) ? 0.5 : 1.0) * (a - b);
      };
      const std::complex<double> cl = c(n - 1);
      for (Eigen::Index j = n - tail; j < n; ++j) {
        const std::complex<double> old = c(j);
        const std::complex<double> now = (j < n - 1 ? old : 0.0) + h[j - (n - tail)] * cl;
        gain2 += std::norm(now) - std::norm(old);
      }
    }
    r.z_sigma_ohm[q] = std::sqrt(std::max(gain2, 0.0) * (g1 * g1 * n1 * n1 + g2 * g2 * n2 * n2));
  }
  r.features = find_features(r.f_hz, r.z_ohm, r.z_sigma_ohm, opt.features);
  return r;
}

}  // namespace piezo::dsp
