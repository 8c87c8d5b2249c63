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

// Issue 19: what a normal run uses instead of the refusal.
TEST(Rayleigh, NormalRunGetsTheOneParameterDampingTheModesSupport) {
  // α < 0: ζ rising faster than ω. β only, least squares through both modes:
  // β = Σ(2ωζ·ω²)/Σω⁴, its sigma from the two modes' scatter about it.
  const double f1 = 50e3, f2 = 100e3, z1 = 0.001, z2 = 0.01;
  const auto s = damping_from_modes(f1, z1, f2, z2);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(s.model, "stiffness-proportional (beta only)");
  EXPECT_EQ(s.damping.alpha, 0.0);
  const double w1 = 2 * M_PI * f1, w2 = 2 * M_PI * f2;
  const double y1 = 2 * z1 * w1, y2 = 2 * z2 * w2, x1 = w1 * w1, x2 = w2 * w2;
  const double b = (x1 * y1 + x2 * y2) / (x1 * x1 + x2 * x2);
  EXPECT_NEAR(s.damping.beta, b, 1e-12 * b);
  const double res = std::hypot(y1 - b * x1, y2 - b * x2);
  EXPECT_NEAR(s.beta_sigma, res / std::hypot(x1, x2), 1e-12 * b);
  EXPECT_GT(s.beta_sigma, 0);
  EXPECT_NEAR(s.qm1, 500.0, 1e-9);
  EXPECT_NEAR(s.qm2, 50.0, 1e-9);
  EXPECT_NE(s.note.find("alpha"), std::string::npos) << s.note;
  // β < 0: ζ falling faster than 1/ω. α only: α = mean of 2ωζ.
  const auto m = damping_from_modes(50e3, 0.02, 100e3, 0.005);
  ASSERT_TRUE(m.ok) << m.message;
  EXPECT_EQ(m.model, "mass-proportional (alpha only)");
  EXPECT_EQ(m.damping.beta, 0.0);
  EXPECT_NEAR(m.damping.alpha, 0.5 * (2 * 0.02 * w1 + 2 * 0.005 * w2), 1e-9);
  // A physical pair: the two-parameter solution itself (no sigma: no dof left).
  const auto p = damping_from_modes(51400, 0.012, 82600, 0.015);
  ASSERT_TRUE(p.ok);
  EXPECT_EQ(p.model, "rayleigh (alpha, beta)");
  EXPECT_EQ(p.damping.beta, rayleigh_from_damping(51400, 0.012, 82600, 0.015).damping.beta);
  EXPECT_TRUE(std::isnan(p.beta_sigma));
  // Unusable input is still refused.
  EXPECT_FALSE(damping_from_modes(50e3, 0.01, 50e3, 0.01).ok);
  EXPECT_FALSE(damping_from_modes(40e3, NAN, 50e3, 0.01).ok);
}

TEST(Rayleigh, DegenerateInputsAreRefused) {
  EXPECT_FALSE(rayleigh_from_damping(50e3, 0.01, 50e3, 0.01).ok);
  EXPECT_FALSE(rayleigh_from_damping(-1, 0.01, 50e3, 0.01).ok);
  EXPECT_FALSE(rayleigh_from_damping(40e3, NAN, 50e3, 0.01).ok);
}

}  // namespace
}  // namespace piezo::update
