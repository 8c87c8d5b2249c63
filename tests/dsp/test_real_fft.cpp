// dsp::RealFft (dsp/fft): the transform against the DFT's sum, and instances
// of one size alive together, on two threads, and after many other sizes, all
// giving the DFT's numbers and the same numbers as a lone instance, bit for bit
// (written for a shared plan cache, which was measured, gave no speed, and was
// taken out: docs/benchmarks.md; the properties hold either way).
#include "dsp/fft.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <random>
#include <thread>
#include <vector>

using piezo::dsp::RealFft;

namespace {

std::vector<double> noise(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01;
  std::vector<double> x(n);
  for (auto& v : x) v = n01(rng);
  return x;
}

std::vector<std::complex<double>> forward(std::size_t n, const std::vector<double>& x) {
  RealFft f(n);
  std::vector<std::complex<double>> out(f.bins());
  f.forward(x.data(), x.size(), out.data());
  return out;
}

}  // namespace

TEST(RealFft, ForwardIsTheDftSumAndInverseUndoesIt) {
  for (std::size_t n : {2u, 3u, 7u, 100u, 1024u, 6000u}) {
    const auto x = noise(n, static_cast<unsigned>(n));
    const auto big = forward(n, x);
    for (std::size_t k = 0; k < big.size(); k += std::max<std::size_t>(1, big.size() / 9)) {
      std::complex<double> s = 0;
      for (std::size_t i = 0; i < n; ++i) s += x[i] * std::polar(1.0, -2.0 * M_PI * double(k * i % n) / double(n));
      EXPECT_LT(std::abs(s - big[k]), 1e-13 * double(n)) << n << " " << k;  // the sum's own round-off grows as ε·n
    }
    RealFft f(n);
    std::vector<double> y(n);
    f.inverse(big.data(), y.data(), n);
    for (std::size_t i = 0; i < n; ++i) EXPECT_NEAR(y[i] / double(n), x[i], 1e-12);
  }
}

TEST(RealFft, InstancesGiveTheSameNumbersTogetherOnThreadsAndAfterOtherSizes) {
  const std::size_t n = 4096;
  const auto x = noise(n, 7);
  const auto alone = forward(n, x);
  {
    RealFft a(n), b(n);  // two instances of one size
    std::vector<std::complex<double>> ya(a.bins()), yb(b.bins());
    a.forward(x.data(), n, ya.data());
    b.forward(x.data(), n, yb.data());
    EXPECT_EQ(ya, alone);
    EXPECT_EQ(yb, alone);
  }
  // Many other sizes made and destroyed in between.
  for (std::size_t m = 100; m < 100 + 2 * 40; m += 2) forward(m, noise(m, 1));
  EXPECT_EQ(forward(n, x), alone);
  // Two threads on the same sizes at once.
  std::vector<std::vector<std::complex<double>>> got(2);
  auto work = [&](int t) {
    for (int i = 0; i < 50; ++i) {
      for (std::size_t m = 200; m < 260; m += 4) forward(m, noise(m, 3));
      got[static_cast<std::size_t>(t)] = forward(n, x);
    }
  };
  std::thread t0(work, 0), t1(work, 1);
  t0.join();
  t1.join();
  EXPECT_EQ(got[0], alone);
  EXPECT_EQ(got[1], alone);
}
