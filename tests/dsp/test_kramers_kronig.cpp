// Vector fitting and the Kramers–Kronig / passivity check on impedances known
// in closed form: the analytic BVD transducer (causal, passive) passes; its
// divider measured with channel 2 late by 400 ns looks active and fails; its
// time reverse (anti-causal: the conjugate response) fails the causality fit.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

#include "bvd_model.hpp"
#include "dsp/kramers_kronig.hpp"
#include "dsp/vector_fitting.hpp"

namespace {
using namespace piezo;
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

Eigen::VectorXd grid() {
  Eigen::VectorXd f(600);
  for (int k = 0; k < 600; ++k) f[k] = 1e3 + 200.0 * k;
  return f;
}

TEST(VectorFitting, FitsAStableRationalFunctionExactly) {
  // H(s) = 0.5 + s·1e-6 + Σ over two resonant pairs and one real pole.
  const cd p1(-2e3, kTwoPi * 30e3), p2(-5e3, kTwoPi * 80e3);
  auto h = [&](cd s) {
    return 0.5 + s * 1e-6 + cd(2e3, 1e3) / (s - p1) + cd(2e3, -1e3) / (s - std::conj(p1)) +
           cd(5e3, 0) / (s - p2) + cd(5e3, 0) / (s - std::conj(p2)) + 4e4 / (s + 2e5);
  };
  const Eigen::VectorXd f = grid();
  Eigen::VectorXcd y(f.size());
  for (Eigen::Index k = 0; k < f.size(); ++k) y[k] = h(cd(0, kTwoPi * f[k]));
  dsp::VectorFitOptions o;
  o.pole_pairs = 3;
  const auto fit = dsp::vector_fit(f, y, Eigen::VectorXd(), o);
  double worst = 0;
  for (Eigen::Index k = 0; k < f.size(); ++k)
    worst = std::max(worst, std::abs(fit.eval(cd(0, kTwoPi * f[k])) / y[k] - 1.0));
  EXPECT_LT(worst, 1e-6);
  for (Eigen::Index k = 0; k < fit.poles.size(); ++k) EXPECT_LT(fit.poles[k].real(), 0.0);
  EXPECT_THROW(dsp::vector_fit(f.head(5), y.head(5), Eigen::VectorXd(), o), std::invalid_argument);
}

TEST(KramersKronig, PassiveCausalTransducerPasses) {
  const auto m = bvd::tube_bvd_q(150);
  const Eigen::VectorXd f = grid();
  Eigen::VectorXcd z(f.size());
  for (Eigen::Index k = 0; k < f.size(); ++k) z[k] = m.impedance_at(f[k]);
  const auto r = dsp::kramers_kronig_check(f, z, Eigen::VectorXd());
  EXPECT_TRUE(r.pass) << r.note;
  EXPECT_TRUE(r.causal && r.passive);
  EXPECT_LT(r.rms_residual, 1e-4);
  EXPECT_EQ(r.residual.size(), f.size());
}

TEST(KramersKronig, LateChannelTwoLooksActiveAndFails) {
  const auto m = bvd::tube_bvd_q(150);
  const Eigen::VectorXd f = grid();
  const double r1 = 3140.0, delay = 400e-9;
  Eigen::VectorXcd z(f.size());
  for (Eigen::Index k = 0; k < f.size(); ++k) {
    const cd zt = m.impedance_at(f[k]);
    const cd t = zt / (zt + r1) * std::exp(cd(0, -kTwoPi * f[k] * delay));
    z[k] = r1 * t / (1.0 - t);
  }
  const auto r = dsp::kramers_kronig_check(f, z, Eigen::VectorXd());
  EXPECT_FALSE(r.pass) << r.note;
  EXPECT_FALSE(r.passive);
  EXPECT_GT(r.max_passivity, 0.05);
}

TEST(KramersKronig, TimeReversedResponseFailsCausality) {
  const auto m = bvd::tube_bvd_q(150);
  const Eigen::VectorXd f = grid();
  Eigen::VectorXcd z(f.size());
  for (Eigen::Index k = 0; k < f.size(); ++k)
    z[k] = std::conj(m.impedance_at(f[k]));  // h(−t): anti-causal, still Re Z ≥ 0
  const auto r = dsp::kramers_kronig_check(f, z, Eigen::VectorXd());
  EXPECT_TRUE(r.passive);
  EXPECT_FALSE(r.causal) << r.note;
  EXPECT_FALSE(r.pass);
}

TEST(KramersKronig, BadInputIsRefused) {
  const Eigen::VectorXd f = grid();
  Eigen::VectorXcd z = Eigen::VectorXcd::Ones(f.size());
  EXPECT_THROW(dsp::kramers_kronig_check(f.head(10), z.head(10), Eigen::VectorXd()),
               std::invalid_argument);
  EXPECT_THROW(dsp::kramers_kronig_check(f, z.head(20), Eigen::VectorXd()), std::invalid_argument);
  z[3] = cd(NAN, 0);
  EXPECT_THROW(dsp::kramers_kronig_check(f, z, Eigen::VectorXd()), std::invalid_argument);
}

}  // namespace
