#include "dsp/fft_ratio.hpp"

#include <cmath>
#include <stdexcept>

#include "dsp/fft.hpp"
#include "dsp/prony_ss.hpp"  // estimate_noise_std

namespace piezo::dsp {

ImpedanceResult impedance_fft(const DividerRecord& rec, const FftRatioOptions& opt) {
  DividerSignals s = prepare_divider(rec, "impedance_fft", opt.prep);
  // Channel noise is white on the recorded samples: measure it before the
  // first difference, whose gain |1 − e^{−jω/fs}| then scales it per bin.
  const double n1 = estimate_noise_std(s.v1), n2 = estimate_noise_std(s.v2);
  if (opt.one_sided) {
    s.v1[0] *= 0.5;
    s.v2[0] *= 0.5;
    s.i[0] *= 0.5;
  }
  if (opt.difference) difference_in_place(s);
  const Eigen::Index n = s.size();
  const std::size_t nfft = opt.nfft ? opt.nfft : static_cast<std::size_t>(n);
  if (nfft < static_cast<std::size_t>(n))
    throw std::invalid_argument("impedance_fft: nfft shorter than the record");
  const Eigen::VectorXd w = make_window(opt.window, n);
  const Eigen::VectorXcd X1 = rfft(s.v1.cwiseProduct(w), nfft);
  const Eigen::VectorXcd X2 = rfft(s.v2.cwiseProduct(w), nfft);
  // White noise σ on a channel gives E|δX|² = σ²·Σw² per bin.
  const double wn = std::sqrt(w.squaredNorm());
  const double e1 = n1 * wn, e2 = n2 * wn;
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
    const double hd = opt.difference ? 2.0 * std::sin(M_PI * double(k) / double(nfft)) : 1.0;
    r.z_sigma_ohm[q] = hd * std::sqrt(g1 * g1 * e1 * e1 + g2 * g2 * e2 * e2);
  }
  r.features = find_features(r.f_hz, r.z_ohm, r.z_sigma_ohm, opt.features);
  return r;
}

}  // namespace piezo::dsp
