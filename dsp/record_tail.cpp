#include "dsp/record_tail.hpp"

#include <algorithm>
#include <cmath>

namespace piezo::dsp {

namespace {
// White-noise σ of a stretch from its first differences (var Δ = 2σ²; the
// signal's own slope taken out).
double tail_noise(const Eigen::VectorXd& t) {
  const Eigen::Index m = t.size();
  if (m < 3) return 0.0;
  const double slope = (t[m - 1] - t[0]) / double(m - 1);
  double d2 = 0;
  for (Eigen::Index k = 1; k < m; ++k) d2 += std::pow(t[k] - t[k - 1] - slope, 2);
  return std::sqrt(d2 / double(m - 1) / 2.0);
}

// Line over the last N/64 samples (8…1024): its value at the last sample when
// it fits within the noise (residual ≤ 1.5σ), else the last sample.
double line_end_level(const Eigen::VectorXd& v) {
  const Eigen::Index n = v.size();
  const Eigen::Index m = std::clamp<Eigen::Index>(n / 64, 8, 1024);
  if (n < 2 * m) return n > 0 ? v[n - 1] : 0.0;
  const Eigen::VectorXd tail = v.tail(m);
  const double tc = 0.5 * double(m - 1);
  double sy = 0, sty = 0, stt = 0;
  for (Eigen::Index k = 0; k < m; ++k) {
    const double t = double(k) - tc;
    sy += tail[k];
    sty += t * tail[k];
    stt += t * t;
  }
  const double a = sy / double(m), b = sty / stt;
  double res2 = 0;
  for (Eigen::Index k = 0; k < m; ++k) res2 += std::pow(tail[k] - (a + b * (double(k) - tc)), 2);
  const double res_sd = std::sqrt(res2 / double(m - 2));
  if (!(res_sd <= 1.5 * tail_noise(tail))) return v[n - 1];
  return a + b * tc;
}
}  // namespace

RecordTail measure_tail(const Eigen::VectorXd& drive) {
  RecordTail t;
  const Eigen::Index n = drive.size(), q = n / 4, h = q / 2;
  if (h < 16) return t;
  const Eigen::VectorXd tail = drive.tail(2 * h);
  const double s1 = tail.head(h).sum(), s2 = tail.tail(h).sum();
  const double sigma_sum = tail_noise(tail) * std::sqrt(double(h));
  if (!(std::fabs(s1) > 10 * sigma_sum) || s1 * s2 <= 0) return t;
  const double ratio = s2 / s1;  // r^h
  if (ratio > 1.05) return t;     // growing: no decay to continue
  if (ratio >= 1.0) {             // settled at a level (a step): r = 1, c from the whole tail
    t.decaying = true;
    return t;
  }
  t.decaying = true;
  t.r = std::pow(ratio, 1.0 / double(h));
  return t;
}

TailCorrection::TailCorrection(const Eigen::VectorXd& v, const RecordTail& tail) : r_(tail.r), n_(v.size()) {
  if (n_ == 0) return;
  last_ = v[n_ - 1];
  if (!tail.decaying) {
    c_ = line_end_level(v);
    r_ = 1.0;
    return;
  }
  // c by least squares over the last quarter with r fixed: v[N−1−m] = c·r^{−m}.
  const Eigen::Index q = std::max<Eigen::Index>(n_ / 4, 1);
  double num = 0, den = 0, g = 1.0;
  for (Eigen::Index m = 0; m < q; ++m) {  // g = r^{−m}, walking back from the end
    num += v[n_ - 1 - m] * g;
    den += g * g;
    g /= r_;
  }
  c_ = num / den;
}

std::complex<double> TailCorrection::at_bin(Eigen::Index k) const {
  const double w = 2 * M_PI * double(k) / double(n_);
  std::complex<double> corr = c_ - last_;
  if (r_ != 1.0) corr += c_ * (r_ - 1.0) / (1.0 - r_ * std::exp(std::complex<double>(0, -w)));
  return corr;
}

}  // namespace piezo::dsp
