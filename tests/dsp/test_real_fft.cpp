// dsp::RealFft (dsp/fft): the transform against the DFT's sum, and instances
// of one size alive together, on two threads, and after many other sizes, all
// giving the DFT's numbers and the same numbers as a lone instance, bit for bit
// (the plans are shared per size, each direction made on its first use, and
// past the cache's limit of sizes an instance's own).
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

// Each direction's plan is made on its first use: an instance made before its
// size had any plan, one whose first transform is an inverse, and sizes past
// the shared cache's limit (their own plans) all give the DFT's numbers, and
// two instances of a size the same bits whichever planned it.
TEST(RealFft, EachDirectionPlannedOnFirstUseGivesTheDftNumbers) {
  auto check = [](std::size_t n, unsigned seed) {
    const auto x = noise(n, seed);
    std::vector<std::complex<double>> dft(n / 2 + 1);
    for (std::size_t k = 0; k < dft.size(); ++k)
      for (std::size_t i = 0; i < n; ++i) dft[k] += x[i] * std::polar(1.0, -2.0 * M_PI * double(k * i % n) / double(n));
    RealFft early(n);  // no plan of this size yet
    RealFft inverse_first(n);
    std::vector<double> y(n);
    inverse_first.inverse(dft.data(), y.data(), n);
    for (std::size_t i = 0; i < n; ++i) ASSERT_NEAR(y[i] / double(n), x[i], 1e-12) << n << " " << i;
    std::vector<std::complex<double>> a(early.bins()), b(early.bins());
    early.forward(x.data(), n, a.data());
    inverse_first.forward(x.data(), n, b.data());
    for (std::size_t k = 0; k < a.size(); ++k) ASSERT_LT(std::abs(a[k] - dft[k]), 1e-13 * double(n)) << n << " " << k;
    EXPECT_EQ(a, b) << n;
    early.inverse(a.data(), y.data(), n);  // the inverse planned by the other instance
    for (std::size_t i = 0; i < n; ++i) ASSERT_NEAR(y[i] / double(n), x[i], 1e-12) << n << " " << i;
  };
  check(1500, 21);
  for (std::size_t m = 301; m < 301 + 2 * 70; m += 2) forward(m, noise(m, 5));  // 70 more sizes: past the limit (64)
  check(1502, 22);  // its own plans
  check(1500, 23);  // still the shared ones
}
