#include "dsp/stepped_sine.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>

#include "dsp/divider.hpp"

namespace piezo::dsp {

Phasor lock_in(std::span<const double> x, double fs, double f) {
  if (x.size() < 8) throw std::invalid_argument("lock_in: need at least 8 samples");
  if (!(fs > 0) || !(f > 0) || !(f < fs / 2))
    throw std::invalid_argument("lock_in: need 0 < f < fs/2");
  const auto n = static_cast<Eigen::Index>(x.size());
  Eigen::MatrixXd a(n, 3);
  Eigen::Map<const Eigen::VectorXd> y(x.data(), n);
  const double w = 2.0 * std::numbers::pi * f / fs;
  for (Eigen::Index k = 0; k < n; ++k) a.row(k) << 1.0, std::cos(w * double(k)), std::sin(w * double(k));
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  const Eigen::Vector3d c = qr.solve(y);
  const double s2 = (y - a * c).squaredNorm() / double(std::max<Eigen::Index>(n - 3, 1));
  const Eigen::Matrix3d cov = s2 * (a.transpose() * a).inverse();
  Phasor p;
  p.value = {c[1], -c[2]};  // b cos + c sin = Re{(b − jc) e^{jωt}}
  p.sigma = std::sqrt(std::max(0.0, cov(1, 1) + cov(2, 2)));
  p.offset = c[0];
  return p;
}

ImpedanceResult impedance_stepped_sine(std::span<const SineShot> shots, const SteppedSineOptions& opt) {
  if (shots.size() < 1) throw std::invalid_argument("impedance_stepped_sine: no shot");
  std::vector<std::size_t> order(shots.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return shots[a].frequency_hz < shots[b].frequency_hz; });
  const auto n = static_cast<Eigen::Index>(shots.size());
  ImpedanceResult r;
  r.method = "sine";
  r.f_hz.resize(n);
  r.z_ohm.resize(n);
  r.z_sigma_ohm.resize(n);
  DividerPrep prep;
  prep.refuse_clipped = opt.refuse_clipped;
  for (Eigen::Index q = 0; q < n; ++q) {
    const SineShot& sh = shots[order[static_cast<std::size_t>(q)]];
    const DividerSignals s = prepare_divider(sh.record, "impedance_stepped_sine", prep);
    const double fs = s.sample_rate_hz, f = sh.frequency_hz;
    if (!(f > 0) || !(f < fs / 2))
      throw std::invalid_argument("impedance_stepped_sine: frequency " + std::to_string(f) +
                                  " Hz outside (0, fs/2)");
    const double settle = opt.settle_s > 0 ? opt.settle_s : opt.settle_fraction * double(s.size()) / fs;
    auto start = static_cast<Eigen::Index>(std::ceil(settle * fs));
    Eigen::Index len = s.size() - start;
    if (opt.whole_periods) {
      const double per = fs / f;
      const double periods = std::floor(double(len) / per);
      if (periods >= 1) len = static_cast<Eigen::Index>(std::floor(periods * per));
    }
    if (len < 16)
      throw std::invalid_argument("impedance_stepped_sine: fewer than 16 samples after settling at " +
                                  std::to_string(f) + " Hz");
    // Phasors referred to the same sample: the common phase cancels in the ratio.
    const Phasor p1 = lock_in({s.v1.data() + start, static_cast<std::size_t>(len)}, fs, f);
    const Phasor p2 = lock_in({s.v2.data() + start, static_cast<std::size_t>(len)}, fs, f);
    const std::complex<double> d = p1.value - p2.value;
    if (std::abs(d) == 0.0) throw std::invalid_argument("impedance_stepped_sine: no current at " + std::to_string(f) + " Hz");
    r.f_hz[q] = f;
    r.z_ohm[q] = s.r1_ohm * p2.value / d;
    const double g1 = std::abs(r.z_ohm[q] / d), g2 = std::abs(s.r1_ohm * p1.value / (d * d));
    r.z_sigma_ohm[q] = std::sqrt(g1 * g1 * p1.sigma * p1.sigma + g2 * g2 * p2.sigma * p2.sigma);
    r.samples_used += static_cast<std::size_t>(len);
  }
  if (n >= 5) r.features = find_features(r.f_hz, r.z_ohm, r.z_sigma_ohm, opt.features);
  return r;
}

}  // namespace piezo::dsp
