// dsp::DecimatedInverse (dsp/decimated_inverse): every d-th sample of a
// band-limited inverse real DFT against the DFT's sum written out (long
// double) and against RealFft::inverse, on odd and even lengths, with and
// without the Nyquist bin, d = 1 and d sharing no factor with N; the copy
// computes the same numbers on another thread; bad shapes are refused.
#include "dsp/decimated_inverse.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

using piezo::dsp::DecimatedInverse;
using piezo::dsp::RealFft;
using cd = std::complex<double>;

namespace {

std::vector<cd> spectrum(std::size_t k_max, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01;
  std::vector<cd> x(k_max + 1);
  for (auto& v : x) v = {n01(rng), n01(rng)};
  return x;
}

// x[t] = Σ_k X[k] e^{+j2πkt/N} over the Hermitian extension (c2r's convention:
// the imaginary parts of X[0] and X[N/2] do not count).
double direct(const std::vector<cd>& x, std::size_t n, std::size_t t) {
  long double s = x[0].real();
  for (std::size_t k = 1; k < x.size(); ++k) {
    const long double ph = 2.0L * std::numbers::pi_v<long double> * static_cast<long double>((k * t) % n) /
                           static_cast<long double>(n);
    if (2 * k == n)
      s += x[k].real() * std::cos(ph);
    else
      s += 2.0L * (x[k].real() * std::cos(ph) - x[k].imag() * std::sin(ph));
  }
  return static_cast<double>(s);
}

double largest(const std::vector<double>& v) {
  double m = 0;
  for (double a : v) m = std::max(m, std::abs(a));
  return m;
}

}  // namespace

TEST(DecimatedInverse, IsTheInverseDftSumAtEveryDthSample) {
  struct Case {
    std::size_t n, k_max, d, count;
  };
  // (N even and odd; the Nyquist bin included; d = 1; d = 33 against N = 2^7·5^4)
  for (const Case c : {Case{64, 32, 1, 64}, Case{63, 31, 4, 16}, Case{1000, 500, 7, 143}, Case{1000, 40, 33, 31},
                       Case{80000, 3031, 33, 607}, Case{2, 1, 1, 2}}) {
    const auto x = spectrum(c.k_max, static_cast<unsigned>(c.n + c.d));
    DecimatedInverse dinv(c.n, c.k_max, c.d, c.count);
    std::vector<double> got(c.count);
    dinv(x.data(), got.data());
    std::vector<double> want(c.count);
    for (std::size_t m = 0; m < c.count; ++m) want[m] = direct(x, c.n, (c.d * m) % c.n);
    // Rounding: the sum's terms are O(1), K of them, through two FFTs of
    // length L ~ K + count: error ~ eps·√K·log L relative to the samples' size.
    const double tol = 1e-13 * std::sqrt(double(c.k_max) + 1) * std::log2(double(c.n) + 2) * largest(want);
    for (std::size_t m = 0; m < c.count; ++m)
      ASSERT_NEAR(got[m], want[m], tol) << "N " << c.n << " K " << c.k_max << " d " << c.d << " m " << m;
  }
}

TEST(DecimatedInverse, AgreesWithTheFullRealInverse) {
  const std::size_t n = 200000, k_max = 7576, d = 33, count = 1516;  // a held-out chirp's residual
  auto x = spectrum(k_max, 7);
  std::vector<cd> full(n / 2 + 1, cd(0.0, 0.0));
  std::copy(x.begin(), x.end(), full.begin());
  RealFft fft(n);
  std::vector<double> all(n);
  fft.inverse(full.data(), all.data(), n);
  DecimatedInverse dinv(n, k_max, d, count);
  std::vector<double> got(count);
  dinv(x.data(), got.data());
  double scale = 0, err = 0;
  for (std::size_t m = 0; m < count; ++m) {
    scale = std::max(scale, std::abs(all[d * m]));
    err = std::max(err, std::abs(got[m] - all[d * m]));
  }
  EXPECT_GT(scale, 10.0);
  EXPECT_LT(err, 1e-12 * scale) << "largest difference " << err << " of samples up to " << scale;
}

TEST(DecimatedInverse, ACopyComputesTheSameOnAnotherThread) {
  const auto x = spectrum(300, 3);
  DecimatedInverse a(4096, 300, 9, 400);
  DecimatedInverse b(a);
  std::vector<double> ya(400), yb(400);
  std::thread t([&] {
    for (int i = 0; i < 50; ++i) b(x.data(), yb.data());
  });
  for (int i = 0; i < 50; ++i) a(x.data(), ya.data());
  t.join();
  EXPECT_EQ(ya, yb);
}

TEST(DecimatedInverse, RefusesImpossibleShapes) {
  EXPECT_THROW(DecimatedInverse(1, 0, 1, 1), std::invalid_argument);
  EXPECT_THROW(DecimatedInverse(100, 51, 1, 10), std::invalid_argument);  // above N/2
  EXPECT_THROW(DecimatedInverse(100, 10, 0, 10), std::invalid_argument);
  EXPECT_THROW(DecimatedInverse(100, 10, 2, 0), std::invalid_argument);
}
