// The lack-of-fit tests of the output-error fit (lack_of_fit.hpp).
#include "update/output_error/lack_of_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "dsp/fft.hpp"
#include "update/residual_regions.hpp"

namespace piezo::update::oe {

SpectralTest spectral_lack_of_fit(const Eigen::VectorXd& r, const Eigen::VectorXd& shape, double bin_hz) {
  SpectralTest out;
  const std::size_t m = static_cast<std::size_t>(r.size());
  if (m < 32) return out;
  dsp::RealFft fft(m);
  std::vector<cd> x(fft.bins());
  fft.forward(r.data(), m, x.data());
  const double top = shape.maxCoeff();
  std::vector<double> z;
  std::vector<std::size_t> bin;
  for (std::size_t j = 1; j + 1 < fft.bins() && j < static_cast<std::size_t>(shape.size()); ++j) {
    const double e = shape[static_cast<Eigen::Index>(j)];
    if (!(e > 1e-4 * top)) continue;  // outside the band
    z.push_back(std::norm(x[j]) / e);
    bin.push_back(j);
  }
  if (z.size() < 16) return out;
  std::vector<double> sorted = z;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
  const double scale = std::log(2.0) / sorted[sorted.size() / 2];
  for (auto& v : z) v *= scale;
  double best = 0;
  for (int w = 1; w <= 64 && static_cast<std::size_t>(w) <= z.size(); w *= 2) {
    const std::size_t step = std::max(1, w / 2);
    for (std::size_t s0 = 0; s0 + static_cast<std::size_t>(w) <= z.size(); s0 += step) {
      double sum = 0;
      for (int i = 0; i < w; ++i) sum += z[s0 + static_cast<std::size_t>(i)];
      ++out.windows;
      const double lq = log_gamma_tail(w, sum);
      if (lq < best) {
        best = lq;
        out.f_lo = double(bin[s0]) * bin_hz;
        out.f_hi = double(bin[s0 + static_cast<std::size_t>(w) - 1]) * bin_hz;
        out.excess = sum / w;
      }
    }
  }
  out.log10_p = std::min(0.0, (best + std::log(double(out.windows))) / std::log(10.0));
  return out;
}

void judge_lack_of_fit(const FitAnswer& answer, Problem& prob, const OeOptions& opt,
                       OeResult& out) {
  const LmOutcome& best = answer.best;
  const auto& t_best = answer.t;
  const double dof = answer.dof, ch1 = answer.ch1, ch2 = answer.ch2;
  // Lack of fit: χ²/ν beyond what the noise estimate's own scatter allows.
  out.chi2_limit = 1.0 + opt.lack_of_fit_z *
                             std::sqrt(2.0 / dof + (out.noise_dof > 0 ? 2.0 / out.noise_dof : 0.0));
  out.lack_of_fit = out.chi2_per_dof > out.chi2_limit;
  // … or concentrated in frequency, where the global χ² dilutes it among
  // thousands of noise samples (an end mass shifting a few modes).
  if (t_best && best.r.size() > 0) {
    const auto st = spectral_lack_of_fit(best.r, prob.residual_psd(*t_best, ch1, ch2), prob.residual_bin_hz());
    out.band_log10_p = st.log10_p;
    out.band_excess = st.excess;
    out.band_lo_hz = st.f_lo;
    out.band_hi_hz = st.f_hi;
    out.band_windows = st.windows;
    out.lack_of_fit = out.lack_of_fit || st.log10_p < std::log10(opt.lack_of_fit_p);
  }
  if (out.lack_of_fit && t_best)
    if (const auto rs = prob.residual_spectrum(best.x, ch1, ch2)) out.regions = residual_regions(*rs, 2, opt.lack_of_fit_p);
}

}  // namespace piezo::update::oe
