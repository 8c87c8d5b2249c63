// Signal statistics and clipping detection.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "dsp/signal_stats.hpp"

using namespace piezo;

TEST(SignalStats, MinMaxRmsOfASine) {
  std::vector<double> x(10000);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = 2.0 * std::sin(2 * M_PI * i / 100.0);
  auto s = dsp::compute_stats(x);
  EXPECT_NEAR(s.rms, 2.0 / std::sqrt(2.0), 1e-12);  // whole periods: exact
  EXPECT_NEAR(s.max, 2.0, 1e-12);
  EXPECT_NEAR(s.min, -2.0, 1e-12);
  EXPECT_NEAR(s.mean, 0.0, 1e-12);
  EXPECT_FALSE(s.clipped);
}

// A 12-bit quantised sine (the coarsest DAQ we expect) sampled 200 times per
// period must not be flagged: its flat tops are a few samples long.
TEST(SignalStats, QuantisedSineIsNotClipped) {
  const double lsb = 2.0 / 4096;
  std::vector<double> x(20000);
  for (std::size_t i = 0; i < x.size(); ++i)
    x[i] = std::round(std::sin(2 * M_PI * i / 200.0) / lsb) * lsb;
  EXPECT_FALSE(dsp::compute_stats(x).clipped);
}

TEST(SignalStats, PinnedConverterIsClipped) {
  std::vector<double> x(20000);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = std::clamp(1.5 * std::sin(2 * M_PI * i / 200.0), -1.0, 1.0);
  auto s = dsp::compute_stats(x);
  EXPECT_TRUE(s.clipped);
  EXPECT_GT(s.samples_at_limit, 1000u);
}

// A 14-bit quantised, noise-free exp_decay (1 V, 3000 1/s, 2 ms at 10 MS/s)
// ends on one code for hundreds of samples near 0 V: a tail, not a rail.
// Clipped on its positive side, the same record is flagged.
TEST(SignalStats, QuantisedDecayTailIsNotClippedButItsPinnedPeakIs) {
  const double lsb = 1.25 / 8192;
  std::vector<double> x(20000);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = std::round(std::exp(-3000.0 * i / 1e7) / lsb) * lsb;
  EXPECT_FALSE(dsp::compute_stats(x).clipped);
  for (auto& v : x) v = std::min(v, 0.9);
  EXPECT_TRUE(dsp::compute_stats(x).clipped);
}

TEST(SignalStats, KnownRangeUsesTheRange) {
  std::vector<double> x = {0.0, 0.5, 0.99, -0.2};
  dsp::ClipDetection c;
  c.range_v = 1.0;
  EXPECT_FALSE(dsp::compute_stats(x, c).clipped);
  x.push_back(-1.0);
  auto s = dsp::compute_stats(x, c);
  EXPECT_TRUE(s.clipped);
  EXPECT_EQ(s.samples_at_limit, 1u);
}

TEST(SignalStats, EmptyIsAnError) {
  std::vector<double> x;
  EXPECT_THROW(dsp::compute_stats(x), std::invalid_argument);
}
