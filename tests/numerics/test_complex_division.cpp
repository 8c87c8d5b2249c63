// numerics/complex_division.hpp against std::complex's division (libgcc's
// __divdc3) and against exact identities.
#include "numerics/complex_division.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <limits>
#include <random>

namespace {
using cd = std::complex<double>;
using piezo::numerics::divide;
using piezo::numerics::reciprocal;

// Both parts within a few ulp of the quotient's magnitude (Smith's bound;
// __divdc3's is of the same order, so two ulp each way).
void expect_close(cd got, cd want) {
  const double tol = 4.0 * std::numeric_limits<double>::epsilon() * std::abs(want);
  EXPECT_NEAR(got.real(), want.real(), tol);
  EXPECT_NEAR(got.imag(), want.imag(), tol);
}

TEST(ComplexDivision, AgreesWithStdOverManyMagnitudes) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> part(-1.0, 1.0), expo(-150.0, 150.0);
  for (int i = 0; i < 20000; ++i) {
    const cd a(part(rng) * std::pow(10.0, expo(rng) / 5),
               part(rng) * std::pow(10.0, expo(rng) / 5));
    const cd b(part(rng) * std::pow(10.0, expo(rng)), part(rng) * std::pow(10.0, expo(rng)));
    expect_close(divide(a, b), a / b);
  }
}

TEST(ComplexDivision, ExactCases) {
  EXPECT_EQ(divide(cd(6.0, 0.0), cd(2.0, 0.0)), cd(3.0, 0.0));
  EXPECT_EQ(divide(cd(0.0, 6.0), cd(0.0, 2.0)), cd(3.0, 0.0));
  EXPECT_EQ(reciprocal(cd(0.0, 4.0)), cd(0.0, -0.25));
  expect_close(divide(cd(1.0, 2.0), cd(3.0, 4.0)), cd(11.0 / 25.0, 2.0 / 25.0));
  // No overflow where the naive conj(b)/|b|² would: |b|² = 1e400.
  expect_close(reciprocal(cd(1e200, 1e200)), cd(0.5e-200, -0.5e-200));
}

TEST(ComplexDivision, NonFiniteAndZeroDivisorsFollowStd) {
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(divide(cd(1.0, 1.0), cd(inf, 0.0)), cd(1.0, 1.0) / cd(inf, 0.0));
  const cd z = divide(cd(1.0, 0.0), cd(0.0, 0.0));
  EXPECT_TRUE(std::isinf(z.real()) || std::isnan(z.real()));
  EXPECT_TRUE(std::isnan(divide(cd(1.0, 0.0), cd(NAN, 1.0)).real()));
}

}  // namespace
