// Where the output-error residual stands above the noise, and what it looks
// like there (update/residual_regions.hpp), on residual spectra built from
// known misfits plus complex Gaussian noise of the stated variance: the
// region must hold the misfit, the shape fit must return its parameters
// within what the noise allows, and noise alone must give no region.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <random>

#include "update/residual_regions.hpp"

namespace {

using piezo::update::ResidualSpectrum;
using piezo::update::residual_regions;
using cd = std::complex<double>;
constexpr double kTwoPi = 6.283185307179586;

// A divider T = 1/(1 + R1·Y) across a 3.9 nF capacitor, R1 = 1 kΩ, a flat
// filtered drive, 1000 bins of 50 Hz from 10 kHz, noise of variance `var`.
// `misfit(f)` is δT (T_true − T), so e = −L·V1·δT + noise.
template <class F>
ResidualSpectrum spectrum(F misfit, double noise_var, std::uint64_t seed) {
  ResidualSpectrum s;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, std::sqrt(noise_var / 2));
  const double r1 = 1e3, c = 3.9e-9;
  for (int i = 0; i < 1000; ++i) {
    const double f = 10e3 + 50.0 * i, w = kTwoPi * f;
    const cd y(0.0, w * c), t = 1.0 / (1.0 + r1 * y);
    s.f_hz.push_back(f);
    s.y_tube.push_back(y);
    s.t.push_back(t);
    s.dt_dy.push_back(-r1 * t * t);
    s.lv1.push_back(cd(1.0, 0.0));
    s.var.push_back(noise_var);
    s.e.push_back(-misfit(f, y, t) + cd(g(rng), g(rng)));
  }
  return s;
}

TEST(ResidualRegions, NoiseAloneHasNoRegion) {
  int with_region = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const auto s = spectrum([](double, cd, cd) { return cd(0, 0); }, 1e-6, seed);
    with_region += residual_regions(s, 2, 1e-3).empty() ? 0 : 1;
  }
  // Bonferroni at 1e-3 per draw: 20 draws give a region with chance < 2 %.
  EXPECT_EQ(with_region, 0);
}

TEST(ResidualRegions, AnExtraResonanceIsFoundWithItsFrequencyQAndCoupling) {
  // A series R-L-C branch across the capacitor: C_b = k²/(1 − k²)·C for k_eff 0.08, Q 80 at 31.7 kHz.
  const double c = 3.9e-9, k = 0.08, cb = k * k / (1 - k * k) * c, fb = 31.7e3, q = 80;
  auto branch = [&](double f, cd, cd t) {
    const double w = kTwoPi * f, u = f / fb;
    const cd dy = cd(0.0, w * cb) / cd(1 - u * u, u / q);
    return -1e3 * t * t * dy;  // δT = (∂T/∂Y)·δY
  };
  // Noise at 1 % of |T| at the resonance (a few-percent shot averaged over a 50 Hz bin is far quieter).
  const auto s = spectrum(branch, 1e-4, 7);
  const auto regions = residual_regions(s, 2, 1e-3);
  ASSERT_FALSE(regions.empty());
  const auto& g = regions.front();
  EXPECT_LE(g.f_lo_hz, fb);
  EXPECT_GE(g.f_hi_hz, fb);
  EXPECT_EQ(g.kind, "extra resonance") << g.description;
  ASSERT_TRUE(g.resonance.has_value());
  // The resonance is ~0.4 kHz wide and seen at a signal-to-noise of ~100 per bin:
  // its frequency to well within a bin, Q and k_eff to a few percent.
  EXPECT_NEAR(g.resonance->f_hz, fb, 10.0);
  EXPECT_NEAR(g.resonance->q / q, 1.0, 0.05);
  EXPECT_NEAR(g.resonance->k_eff / k, 1.0, 0.05);
  EXPECT_NE(g.description.find("extra resonance at 31.7"), std::string::npos) << g.description;
}

TEST(ResidualRegions, AResonanceNarrowerThanTheRecordResolvesHasOnlyALowerBoundOnQ) {
  // Q 3000 at 31.7 kHz: 10.6 Hz wide, a fifth of a 50 Hz bin — the record cannot tell Q 3000 from 1000.
  const double c = 3.9e-9, k = 0.05, cb = k * k / (1 - k * k) * c, fb = 31.7e3, q = 3000;
  auto branch = [&](double f, cd, cd t) {
    const double u = f / fb;
    return -1e3 * t * t * cd(0.0, kTwoPi * f * cb) / cd(1 - u * u, u / q);
  };
  const auto regions = residual_regions(spectrum(branch, 1e-4, 9), 2, 1e-3);
  ASSERT_FALSE(regions.empty());
  ASSERT_TRUE(regions.front().resonance.has_value()) << regions.front().description;
  const auto& x = *regions.front().resonance;
  EXPECT_NEAR(x.f_hz, fb, 50.0);
  EXPECT_FALSE(x.q_resolved) << "fitted Q " << x.q;
  EXPECT_NEAR(x.q_min, fb / 150.0, 1e-6 * fb);  // f·T_record/3 with 50 Hz bins
  EXPECT_NE(regions.front().description.find("narrower than the record resolves"), std::string::npos);
}

TEST(ResidualRegions, ALevelOffsetIsALevelNotAResonance) {
  // δT = −2 % of T between 30 and 32 kHz (a band-limited gain error).
  auto level = [](double f, cd, cd t) { return (f > 30e3 && f < 32e3) ? -0.02 * t : cd(0, 0); };
  const auto s = spectrum(level, 1e-6, 11);
  const auto regions = residual_regions(s, 2, 1e-3);
  ASSERT_FALSE(regions.empty());
  const auto& g = regions.front();
  EXPECT_LT(g.f_lo_hz, 31e3);
  EXPECT_GT(g.f_hi_hz, 31e3);
  EXPECT_EQ(g.kind, "level") << g.description;
  // The data say δT = −2 % of T with σ ≈ 0.1/|T|/√bins % (≈ 0.01 %): the region may take a noise bin or two at
  // its edges, which pull the fitted level toward zero by their share (< 5 %).
  EXPECT_NEAR(g.level_pct, -2.0, 0.1);
}

TEST(ResidualRegions, TwoSeparateMisfitsAreTwoRegionsStrongestFirst) {
  const double c = 3.9e-9;
  auto two = [&](double f, cd, cd t) {
    auto br = [&](double fb, double k, double q) {
      const double cb = k * k / (1 - k * k) * c, u = f / fb;
      return -1e3 * t * t * cd(0.0, kTwoPi * f * cb) / cd(1 - u * u, u / q);
    };
    return br(25e3, 0.1, 60) + br(45e3, 0.05, 100);
  };
  const auto s = spectrum(two, 1e-4, 3);
  const auto regions = residual_regions(s, 2, 1e-3);
  ASSERT_EQ(regions.size(), 2u);
  auto holds = [](const piezo::update::ResidualRegion& g, double f) { return g.f_lo_hz <= f && f <= g.f_hi_hz; };
  EXPECT_TRUE(holds(regions[0], 25e3)) << regions[0].description;
  EXPECT_TRUE(holds(regions[1], 45e3)) << regions[1].description;
}

}  // namespace
