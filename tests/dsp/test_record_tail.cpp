// dsp/record_tail: the end of a finite record in the spectrum of its first
// difference (what the shot ensemble of the gap diagnosis uses).
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <random>

#include "dsp/fft.hpp"
#include "dsp/record_tail.hpp"

using namespace piezo::dsp;
using cd = std::complex<double>;

namespace {
Eigen::VectorXd differenced(Eigen::VectorXd v) {
  for (Eigen::Index k = v.size() - 1; k > 0; --k) v[k] -= v[k - 1];
  return v;
}
}  // namespace

// A decay still under way when the record ends (the seed's exp_decay drive:
// e^{-6} after 2 ms): with the continuation the corrected DFT is the
// transform of the whole, unending decay (1 − e^{−jω})/(1 − r e^{−jω}).
TEST(RecordTail, ContinuesADecayBeyondTheRecord) {
  const Eigen::Index n = 20000;
  const double r = std::exp(-3000.0 / 1e7);
  Eigen::VectorXd v(n);
  for (Eigen::Index k = 0; k < n; ++k) v[k] = std::pow(r, double(k));
  const RecordTail tail = measure_tail(v);
  ASSERT_TRUE(tail.decaying);
  EXPECT_NEAR(tail.r, r, 1e-12);
  const TailCorrection corr(v, tail);
  const Eigen::VectorXcd d = rfft(differenced(v), static_cast<std::size_t>(n));
  double worst = 0, worst_raw = 0;
  for (Eigen::Index k = 1; k < 1200; ++k) {  // 0.5–600 kHz
    const double w = 2 * M_PI * double(k) / double(n);
    const cd e = std::exp(cd(0, -w));
    const cd exact = (1.0 - e) / (1.0 - r * e);
    worst = std::max(worst, std::abs((d[k] + corr.at_bin(k)) / exact - 1.0));
    worst_raw = std::max(worst_raw, std::abs(d[k] / exact - 1.0));
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_GT(worst_raw, 1e-3);  // without it: the truncation
}

// Noise: the single last sample's noise enters every bin; the fitted end
// level carries far less of it.
TEST(RecordTail, EndLevelCarriesLessNoiseThanTheLastSample) {
  const Eigen::Index n = 20000;
  const double r = std::exp(-3000.0 / 1e7), sigma = 1e-3;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g(0, sigma);
  Eigen::VectorXd clean(n);
  for (Eigen::Index k = 0; k < n; ++k) clean[k] = std::pow(r, double(k));
  // The decay rate from the (quieter) average of 16 records, as the shot ensemble does.
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(n);
  std::vector<Eigen::VectorXd> shots;
  for (int s = 0; s < 16; ++s) {
    Eigen::VectorXd v = clean;
    for (auto& x : v) x += g(rng);
    mean += v / 16.0;
    shots.push_back(v);
  }
  const RecordTail tail = measure_tail(mean);
  ASSERT_TRUE(tail.decaying);
  EXPECT_NEAR(tail.r, r, 0.1 * (1 - r));
  double e_fit = 0, e_last = 0;
  for (const auto& v : shots) {
    const TailCorrection c(v, tail);
    e_fit += std::pow(c.end_level() - clean[n - 1], 2);
    e_last += std::pow(v[n - 1] - clean[n - 1], 2);
  }
  EXPECT_LT(std::sqrt(e_fit / 16), 0.1 * sigma);
  EXPECT_GT(std::sqrt(e_last / 16), 0.5 * sigma);
}

// A burst that rang down (the chirp): nothing to continue; the end level is
// the line through the quiet tail, the last sample of a tail that still rings.
TEST(RecordTail, NoContinuationForARecordThatEndsAtRest) {
  const Eigen::Index n = 20000;
  std::mt19937_64 rng(4);
  std::normal_distribution<double> g(0, 1e-3);
  Eigen::VectorXd v(n);
  for (Eigen::Index k = 0; k < n; ++k) v[k] = (k < 12000 ? std::sin(0.01 * double(k)) : 0.0) + g(rng);
  const RecordTail tail = measure_tail(v);
  EXPECT_FALSE(tail.decaying);
  const TailCorrection c(v, tail);
  EXPECT_LT(std::fabs(c.end_level()), 3e-4);
  EXPECT_EQ(c.at_bin(7), cd(c.end_level() - v[n - 1], 0.0));
  Eigen::VectorXd ringing(n);
  for (Eigen::Index k = 0; k < n; ++k) ringing[k] = std::sin(0.05 * double(k));
  const TailCorrection cr(ringing, measure_tail(ringing));
  EXPECT_EQ(cr.end_level(), ringing[n - 1]);
}
