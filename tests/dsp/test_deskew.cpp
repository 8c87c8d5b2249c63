// Channel deskew: time-domain resampling of a late channel with the drive's
// jump kept on sample 0, the cross-correlation and phase-slope delay
// estimates, and the Z-domain correction (checked in closed form).
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "dsp/deskew.hpp"

namespace {
using namespace piezo;
using cd = std::complex<double>;
constexpr double kFs = 1e7, kTwoPi = 2.0 * std::numbers::pi;

// A channel that jumps at t = 0 by 0.3 V and rises through a 485 ns RC (a
// fixture's v2), then decays with the drive.
double v(double t) {
  return t < 0 ? 0.0 : 0.3 * std::exp(-3000 * t) + 0.7 * (1 - std::exp(-t / 485e-9));
}

TEST(Deskew, ChannelResamplingKeepsTheJumpOnSampleZero) {
  const int n = 3000, pre = 200;
  for (double delay : {0.0, 37e-9, 150e-9, 200e-9, -73e-9}) {
    std::vector<double> x(n);
    for (int k = 0; k < n; ++k) x[k] = v((k - pre) / kFs - delay);
    const auto y = dsp::deskew_channel(x, kFs, pre, delay);
    ASSERT_EQ(y.size(), x.size());
    double worst = 0, at_jump = 0;
    for (int k = 3; k < n - 5; ++k) {  // the ends are extrapolated
      const double e = std::abs(y[k] - v((k - pre) / kFs));
      if (k == pre)
        at_jump = e;
      else
        worst = std::max(worst, e);
    }
    EXPECT_LT(worst, 5e-5) << delay;    // 4-point Lagrange on a 4.85-sample RC rise
    EXPECT_LT(at_jump, 2e-3) << delay;  // the right limit, extrapolated from after the jump
    EXPECT_LT(std::abs(y[pre - 1]), 1e-12) << delay;  // before the jump: the pre-jump side only
  }
  EXPECT_THROW(dsp::deskew_channel(std::vector<double>(3), kFs, 0, 1e-7), std::invalid_argument);
  EXPECT_THROW(dsp::deskew_channel(std::vector<double>(100), kFs, 100, 1e-7),
               std::invalid_argument);
}

TEST(Deskew, CrossCorrelationFindsASubSampleDelay) {
  // A smooth pulse on both channels, channel 2 late by 137 ns (1.37 samples).
  const int n = 4000;
  std::vector<double> a(n), b(n);
  auto pulse = [](double t) { return std::exp(-std::pow((t - 100e-6) / 2e-6, 2)); };
  for (int k = 0; k < n; ++k) {
    a[k] = pulse(k / kFs);
    b[k] = 0.4 * pulse(k / kFs - 137e-9);
  }
  EXPECT_NEAR(dsp::xcorr_delay(a, b, kFs), 137e-9, 2e-9);
  EXPECT_NEAR(dsp::xcorr_delay(b, a, kFs), -137e-9, 2e-9);
  EXPECT_THROW(dsp::xcorr_delay(a, std::vector<double>(10), kFs), std::invalid_argument);
}

TEST(Deskew, ImpedanceCorrectionUndoesAKnownDelay) {
  const double r1 = 3140.0, tau = 180e-9;
  Eigen::VectorXd f(50);
  Eigen::VectorXcd z(50), zm(50), t(50);
  for (int k = 0; k < 50; ++k) {
    f[k] = 2.4e3 * (k + 1);
    z[k] = 1.0 / cd(1e-5, kTwoPi * f[k] * 15e-9);                              // a lossy capacitor
    const cd tt = z[k] / (z[k] + r1) * std::exp(cd(0, -kTwoPi * f[k] * tau));  // channel 2 late
    zm[k] = r1 * tt / (1.0 - tt);
    t[k] = tt;
  }
  const Eigen::VectorXcd back = dsp::deskew_impedance(f, zm, r1, tau);
  for (int k = 0; k < 50; ++k) EXPECT_LT(std::abs(back[k] / z[k] - 1.0), 1e-12);
  // A resistive transfer delayed by τ: the phase slope gives τ.
  Eigen::VectorXcd tl(50);
  for (int k = 0; k < 50; ++k) tl[k] = 0.3 * std::exp(cd(0, -kTwoPi * f[k] * tau));
  EXPECT_NEAR(dsp::phase_slope_delay(f, tl), tau, 1e-15);
  // σ follows the first-order derivative (unchanged for τ = 0).
  dsp::ImpedanceResult r;
  r.f_hz = f;
  r.z_ohm = zm;
  r.z_sigma_ohm = Eigen::VectorXd::Ones(50);
  dsp::deskew_impedance(r, r1, 0.0);
  EXPECT_NEAR(r.z_sigma_ohm[10], 1.0, 1e-12);
}

}  // namespace
