#include "dsp/drive_band.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "dsp/fft.hpp"
#include "dsp/prony_ss.hpp"

namespace piezo::dsp {

DriveBand drive_band(std::span<const double> x, double fs_hz, std::size_t pretrigger, double min_snr) {
  if (x.size() < 64 || !(fs_hz > 0)) throw std::invalid_argument("the drive's band: need >= 64 samples and a sample rate > 0");
  const std::size_t n = x.size();
  Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(x.data(), static_cast<Eigen::Index>(n));
  if (pretrigger >= 16 && pretrigger < n) v.array() -= v.head(static_cast<Eigen::Index>(pretrigger)).mean();
  DriveBand out;
  out.min_snr = min_snr;
  out.noise_std = estimate_noise_std(v);
  const Eigen::VectorXcd spec = rfft(v, n);
  const Eigen::Index bins = spec.size();
  std::vector<double> cum(static_cast<std::size_t>(bins) + 1, 0.0);  // prefix sums of |X_k|²
  for (Eigen::Index k = 0; k < bins; ++k) cum[static_cast<std::size_t>(k) + 1] = cum[static_cast<std::size_t>(k)] + std::norm(spec[k]);
  const double floor = static_cast<double>(n) * out.noise_std * out.noise_std;
  const double r = std::pow(2.0, 1.0 / 6.0);
  Eigen::Index lo = -1, hi = -1;
  for (Eigen::Index k = 1; k < bins; ++k) {
    const auto a = std::max<Eigen::Index>(1, static_cast<Eigen::Index>(std::floor(double(k) / r)));
    const auto b = std::min<Eigen::Index>(bins - 1, static_cast<Eigen::Index>(std::ceil(double(k) * r)));
    const double p = (cum[static_cast<std::size_t>(b) + 1] - cum[static_cast<std::size_t>(a)]) / double(b - a + 1);
    const double snr = floor > 0 ? std::sqrt(std::max(0.0, p - floor) / floor) : INFINITY;
    if (snr >= min_snr) {
      if (lo < 0) lo = k;
      hi = k;
    }
  }
  const double df = fs_hz / static_cast<double>(n);
  char buf[240];
  if (lo < 0) {
    std::snprintf(buf, sizeof buf, "no DFT bin of the drive stands %.3g times above its noise floor (sigma %.3g V)",
                  min_snr, out.noise_std);
    out.note = buf;
    return out;
  }
  out.found = true;
  out.lo_hz = double(lo) * df;
  out.hi_hz = double(hi) * df;
  std::snprintf(buf, sizeof buf,
                "%.4g-%.4g Hz: channel 1's spectrum (third-octave mean) at least %.3g times its white-noise floor "
                "(sigma %.3g V)",
                out.lo_hz, out.hi_hz, min_snr, out.noise_std);
  out.note = buf;
  return out;
}

}  // namespace piezo::dsp
