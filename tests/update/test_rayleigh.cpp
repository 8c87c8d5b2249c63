// update/rayleigh: eqs 166-169 and the refusal of non-physical fits.
#include <gtest/gtest.h>

#include <cmath>

#include "update/rayleigh.hpp"

namespace piezo::update {
namespace {

double zeta(const model::RayleighDamping& d, double f) {
  const double w = 2 * M_PI * f;
  return 0.5 * (d.alpha / w + d.beta * w);  // eq. 167
}

TEST(Rayleigh, ReproducesBothDampingRatios) {
  const auto r = rayleigh_from_damping(51400, 0.012, 82600, 0.015);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_NEAR(zeta(r.damping, 51400), 0.012, 1e-15);
  EXPECT_NEAR(zeta(r.damping, 82600), 0.015, 1e-15);
  EXPECT_GT(r.damping.alpha, 0);
  EXPECT_GT(r.damping.beta, 0);
}

TEST(Rayleigh, PureStiffnessProportional) {
  // Chapter 5: α = 0, β = 1e-7 s → ζ = βω/2 at every mode.
  const double b = 1e-7, f1 = 50e3, f2 = 95e3;
  const auto r = rayleigh_from_damping(f1, 0.5 * b * 2 * M_PI * f1, f2, 0.5 * b * 2 * M_PI * f2);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_NEAR(r.damping.alpha, 0, 1e-9);
  EXPECT_NEAR(r.damping.beta, b, 1e-18);
}

TEST(Rayleigh, NegativeCoefficientIsRefusedWithAMessage) {
  // ζ falling faster than 1/ω between the modes needs β < 0.
  const auto r = rayleigh_from_damping(50e3, 0.02, 100e3, 0.005);
  EXPECT_FALSE(r.ok);
  EXPECT_LT(r.damping.beta, 0);
  EXPECT_NE(r.message.find("negative"), std::string::npos) << r.message;
  // ζ rising faster than ω needs α < 0.
  const auto s = rayleigh_from_damping(50e3, 0.001, 100e3, 0.01);
  EXPECT_FALSE(s.ok);
  EXPECT_LT(s.damping.alpha, 0);
}

TEST(Rayleigh, DegenerateInputsAreRefused) {
  EXPECT_FALSE(rayleigh_from_damping(50e3, 0.01, 50e3, 0.01).ok);
  EXPECT_FALSE(rayleigh_from_damping(-1, 0.01, 50e3, 0.01).ok);
  EXPECT_FALSE(rayleigh_from_damping(40e3, NAN, 50e3, 0.01).ok);
}

}  // namespace
}  // namespace piezo::update
