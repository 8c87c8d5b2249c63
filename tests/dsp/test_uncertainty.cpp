// Uncertainty bands: σ from a circular per-point σ and from replicates, the
// coverage test of a band, the bootstrap's resampling; and, on known Gaussian
// scatter, that a k = 1.96 band covers about 95 % of the draws.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <random>

#include "dsp/uncertainty.hpp"

namespace {
using namespace piezo;
using cd = std::complex<double>;

TEST(Uncertainty, BandFromCircularSigma) {
  Eigen::VectorXd f(2), s(2);
  Eigen::VectorXcd z(2);
  f << 1e3, 2e3;
  z << cd(0, -100), cd(30, -40);
  s << 2.0, 1.0;
  const auto b = dsp::band_from_sigma(f, z, s);
  EXPECT_NEAR(b.abs_ohm[1], 50.0, 1e-12);
  EXPECT_NEAR(b.abs_sigma_ohm[0], 2.0 / std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(b.phase_sigma_rad[0], 2.0 / (std::sqrt(2.0) * 100.0), 1e-12);
  EXPECT_TRUE(b.covers(0, cd(0, -101)));
  EXPECT_FALSE(b.covers(0, cd(0, -104)));
  EXPECT_FALSE(b.covers(0, cd(3, -100)));  // 1.7° off: outside ±1.96·0.81°
  EXPECT_THROW(dsp::band_from_sigma(f, z, Eigen::VectorXd(3)), std::invalid_argument);
}

TEST(Uncertainty, ReplicatesGiveTheirSpreadAndCoverAbout95Percent) {
  const int n = 400;
  Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(n, 1e3, 1e5);
  Eigen::VectorXcd truth(n);
  for (int k = 0; k < n; ++k) truth[k] = cd(10, -1000.0 * (1 + k % 7));
  std::mt19937_64 rng(5);
  std::normal_distribution<double> nd;
  const double rel = 0.01, ph = 0.005;
  auto draw = [&] {
    Eigen::VectorXcd z(n);
    for (int k = 0; k < n; ++k)
      z[k] = truth[k] * (1 + rel * nd(rng)) * std::exp(cd(0, ph * nd(rng)));
    return z;
  };
  std::vector<Eigen::VectorXcd> reps;
  for (int b = 0; b < 200; ++b) reps.push_back(draw());
  const Eigen::VectorXcd est = draw();  // an estimate with the same scatter
  const auto band = dsp::band_from_replicates(f, est, reps, 0);
  EXPECT_NEAR(band.abs_sigma_ohm[5] / band.abs_ohm[5], rel, 0.15 * rel);
  EXPECT_NEAR(band.phase_sigma_rad[5], ph, 0.15 * ph);
  // The band around the estimate covers the truth ~ P(|x| < 1.96σ√… ) for both: est and truth
  // differ by one draw, so |Z| and phase each cover ~95 %: together ~90 %.
  int in = 0;
  for (int k = 0; k < n; ++k) in += band.covers(k, truth[k]);
  EXPECT_GT(in, int(0.85 * n));
  EXPECT_LT(in, int(0.97 * n));
  EXPECT_THROW(dsp::band_from_replicates(f, est, {reps[0]}, 0), std::invalid_argument);
}

TEST(Uncertainty, BootstrapResamplesWithReplacementAndSkipsRefusals) {
  std::vector<std::vector<std::size_t>> seen;
  int calls = 0;
  auto reps = dsp::bootstrap_over_shots(5, 20, 9, [&](const std::vector<std::size_t>& idx) {
    seen.push_back(idx);
    if (++calls % 4 == 0) throw std::invalid_argument("degenerate");
    return Eigen::VectorXcd::Constant(3, cd(double(idx[0]), 0));
  });
  EXPECT_EQ(reps.size(), 15u);
  for (const auto& s : seen) {
    EXPECT_EQ(s.size(), 5u);
    for (auto i : s) EXPECT_LT(i, 5u);
  }
  bool repeated = false;  // with replacement: some draw holds a shot twice
  for (const auto& s : seen)
    for (std::size_t a = 0; a < s.size(); ++a)
      for (std::size_t b = a + 1; b < s.size(); ++b) repeated = repeated || s[a] == s[b];
  EXPECT_TRUE(repeated);
  const auto again = dsp::bootstrap_over_shots(5, 3, 9, [](const std::vector<std::size_t>& idx) {
    return Eigen::VectorXcd::Constant(1, cd(double(idx[0] * 10 + idx[1]), 0));
  });
  const auto twice = dsp::bootstrap_over_shots(5, 3, 9, [](const std::vector<std::size_t>& idx) {
    return Eigen::VectorXcd::Constant(1, cd(double(idx[0] * 10 + idx[1]), 0));
  });
  for (int b = 0; b < 3; ++b) EXPECT_EQ(again[b][0], twice[b][0]);  // seeded
  EXPECT_THROW(dsp::bootstrap_over_shots(
                   1, 3, 9, [](const std::vector<std::size_t>&) { return Eigen::VectorXcd(); }),
               std::invalid_argument);
}

}  // namespace
