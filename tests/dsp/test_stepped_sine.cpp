// Stepped-sine lock-in: exact phasors on steady-state sines, the settling skip,
// and a per-point σ that matches the scatter over noise seeds.
#include "dsp/stepped_sine.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "bvd_model.hpp"

namespace {
using namespace piezo;
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Steady state of the divider at f: v1 = cos ωt, v2 = Re{T e^{jωt}}, T = Z/(Z + R1);
// the first quarter carries a decaying transient the estimator must skip.
struct SineCase {
  std::vector<double> v1, v2;
  SineCase(const bvd::Bvd& m, double f, double fs, std::size_t n, double noise, std::uint64_t seed) {
    const cd z = m.impedance_at(f), t = z / (z + 3140.0);
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> nd(0.0, noise);
    for (std::size_t k = 0; k < n; ++k) {
      const double tt = double(k) / fs;
      const double tr = 0.3 * std::exp(-tt * fs / (0.01 * double(n)));
      v1.push_back(std::cos(kTwoPi * f * tt) + nd(rng));
      v2.push_back((t * std::exp(cd(0, kTwoPi * f * tt))).real() + tr + nd(rng));
    }
  }
};

TEST(SteppedSine, ExactOnSteadyState) {
  const auto m = bvd::tube_bvd_q(100);
  std::vector<SineCase> cases;
  std::vector<dsp::SineShot> shots;
  for (double f = 40e3; f <= 100e3; f += 240) cases.emplace_back(m, f, 2e6, 4000, 0.0, 1);
  double f = 40e3;
  for (const auto& c : cases) {
    shots.push_back({{c.v1, c.v2, 2e6, 3140.0, 0, {}}, f});
    f += 240;
  }
  const auto r = dsp::impedance_stepped_sine(shots);
  double worst = 0;
  for (Eigen::Index q = 0; q < r.f_hz.size(); ++q)
    worst = std::max(worst, std::abs(r.z_ohm[q] / m.impedance_at(r.f_hz[q]) - 1.0));
  EXPECT_LT(worst, 1e-6);  // the transient is down to 0.3·e^{-25} where the fit starts
  ASSERT_EQ(r.features.resonances.size(), 3u);
  ASSERT_EQ(r.features.antiresonances.size(), 3u);
}

TEST(SteppedSine, SigmaMatchesScatter) {
  const auto m = bvd::tube_bvd_q(100);
  const double f = 60e3;
  std::vector<cd> z;
  double sigma = 0;
  for (std::uint64_t s = 0; s < 200; ++s) {
    const SineCase c(m, f, 2e6, 4000, 0.01, 100 + s);
    const dsp::SineShot shot{{c.v1, c.v2, 2e6, 3140.0, 0, {}}, f};
    const auto r = dsp::impedance_stepped_sine({&shot, 1});
    z.push_back(r.z_ohm[0]);
    sigma += r.z_sigma_ohm[0] / 200.0;
  }
  cd mean = 0;
  for (auto v : z) mean += v / 200.0;
  double var = 0;
  for (auto v : z) var += std::norm(v - mean) / 199.0;
  // σ of a σ estimate from 200 samples: ±5 %; allow 20 %.
  EXPECT_NEAR(sigma / std::sqrt(var), 1.0, 0.2);
}

TEST(SteppedSine, Refusals) {
  const auto m = bvd::tube_bvd_q(100);
  const SineCase c(m, 60e3, 2e6, 4000, 0.0, 1);
  dsp::SineShot shot{{c.v1, c.v2, 2e6, 3140.0, 0, {}}, 1.5e6};
  EXPECT_THROW(dsp::impedance_stepped_sine({&shot, 1}), std::invalid_argument);
  EXPECT_THROW(dsp::impedance_stepped_sine({}), std::invalid_argument);
}

}  // namespace
