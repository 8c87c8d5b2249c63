#include "dsp/cross_spectra.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "dsp/fft.hpp"

namespace piezo::dsp {

CrossSpectra cross_spectra(std::span<const DividerRecord> records, const CrossSpectraOptions& opt) {
  if (records.empty()) throw std::invalid_argument("cross_spectra: no record");
  if (!(opt.overlap >= 0.0 && opt.overlap <= 0.95))
    throw std::invalid_argument("cross_spectra: overlap must be in [0, 0.95]");
  std::vector<DividerSignals> sig;
  for (const auto& r : records) {
    sig.push_back(prepare_divider(r, "cross_spectra", opt.prep));
    if (opt.difference) difference_in_place(sig.back());
  }
  const double fs = sig[0].sample_rate_hz, r1 = sig[0].r1_ohm;
  Eigen::Index shortest = sig[0].size();
  for (const auto& s : sig) {
    if (s.sample_rate_hz != fs || s.r1_ohm != r1)
      throw std::invalid_argument("cross_spectra: records differ in sample rate or R1");
    shortest = std::min(shortest, s.size());
  }
  const auto seg = opt.segment ? static_cast<Eigen::Index>(opt.segment) : shortest;
  if (seg < 16 || seg > shortest)
    throw std::invalid_argument("cross_spectra: segment of " + std::to_string(seg) +
                                " samples does not fit the records (shortest " + std::to_string(shortest) + ")");
  const auto hop = std::max<Eigen::Index>(1, static_cast<Eigen::Index>(std::llround(double(seg) * (1.0 - opt.overlap))));
  const Eigen::VectorXd w = make_window(opt.window, seg);
  RealFft fft(static_cast<std::size_t>(seg));
  const auto bins = static_cast<Eigen::Index>(fft.bins());
  CrossSpectra cs;
  cs.r1_ohm = r1;
  cs.g11 = Eigen::VectorXd::Zero(bins);
  cs.g22 = Eigen::VectorXd::Zero(bins);
  cs.g12 = Eigen::VectorXcd::Zero(bins);
  Eigen::VectorXcd x1(bins), x2(bins);
  Eigen::VectorXd b1(seg), b2(seg);
  for (const auto& s : sig) {
    for (Eigen::Index start = 0; start + seg <= s.size(); start += hop) {
      b1 = s.v1.segment(start, seg).cwiseProduct(w);
      b2 = s.v2.segment(start, seg).cwiseProduct(w);
      fft.forward(b1.data(), static_cast<std::size_t>(seg), x1.data());
      fft.forward(b2.data(), static_cast<std::size_t>(seg), x2.data());
      cs.g11 += x1.cwiseAbs2();
      cs.g22 += x2.cwiseAbs2();
      cs.g12 += x1.conjugate().cwiseProduct(x2);
      ++cs.segments;
    }
  }
  const double inv = 1.0 / double(cs.segments);
  cs.g11 *= inv;
  cs.g22 *= inv;
  cs.g12 *= inv;
  cs.f_hz = Eigen::VectorXd::LinSpaced(bins, 0.0, fs / double(seg) * double(bins - 1));
  cs.h1 = cs.g12.cwiseQuotient(cs.g11.cast<std::complex<double>>());
  cs.h2 = cs.g22.cast<std::complex<double>>().cwiseQuotient(cs.g12.conjugate());
  cs.h161.resize(bins);
  cs.coherence.resize(bins);
  for (Eigen::Index k = 0; k < bins; ++k) {
    cs.h161[k] = std::sqrt(std::abs(cs.h1[k] * cs.h2[k])) * std::exp(std::complex<double>(0, std::arg(cs.h1[k])));
    cs.coherence[k] = std::norm(cs.g12[k]) / (cs.g11[k] * cs.g22[k]);
  }
  return cs;
}

ImpedanceResult impedance_xspec(std::span<const DividerRecord> records, const CrossSpectraOptions& opt) {
  const CrossSpectra cs = cross_spectra(records, opt);
  const Eigen::VectorXcd& t = opt.estimator == SpectralEstimator::H1   ? cs.h1
                              : opt.estimator == SpectralEstimator::H2 ? cs.h2
                                                                       : cs.h161;
  const double fmax = opt.fmax_hz > 0 ? opt.fmax_hz : cs.f_hz[cs.f_hz.size() - 1];
  std::vector<Eigen::Index> keep;
  for (Eigen::Index k = 1; k < cs.f_hz.size(); ++k)
    if (cs.f_hz[k] >= opt.fmin_hz && cs.f_hz[k] <= fmax) keep.push_back(k);
  if (keep.size() < 2) throw std::invalid_argument("impedance_xspec: fewer than 2 bins in [fmin, fmax]");
  const auto m = static_cast<Eigen::Index>(keep.size());
  ImpedanceResult r;
  r.method = opt.estimator == SpectralEstimator::H1 ? "xspec-h1"
             : opt.estimator == SpectralEstimator::H2 ? "xspec-h2" : "xspec-eq161";
  r.samples_used = cs.segments * static_cast<std::size_t>(2 * (cs.f_hz.size() - 1));
  r.f_hz.resize(m);
  r.z_ohm.resize(m);
  r.z_sigma_ohm.resize(m);
  r.coherence.resize(m);
  const double nd = double(cs.segments);
  for (Eigen::Index q = 0; q < m; ++q) {
    const Eigen::Index k = keep[static_cast<std::size_t>(q)];
    const std::complex<double> tk = t[k], one_minus = 1.0 - tk;
    r.f_hz[q] = cs.f_hz[k];
    r.z_ohm[q] = cs.r1_ohm * tk / one_minus;
    r.coherence[q] = cs.coherence[k];
    const double g2 = std::clamp(cs.coherence[k], 1e-12, 1.0);
    const double eps = std::sqrt((1.0 - g2) / (2.0 * nd * g2));
    const double sigma_t = std::sqrt(2.0) * eps * std::abs(tk);
    r.z_sigma_ohm[q] = cs.r1_ohm / std::norm(one_minus) * sigma_t;
  }
  r.features = find_features(r.f_hz, r.z_ohm, r.z_sigma_ohm, opt.features);
  return r;
}

}  // namespace piezo::dsp
