// Whether a fitted equivalent circuit describes its data (dsp/circuit_adequacy):
// the noise from the data's own scatter against the noise put in, the
// conductance peaks of clear prominence, figures whose σ covers their error
// or that say they are unreliable when the network is the wrong model, and the
// plausibility checks on constructed fits.
#include "dsp/circuit_adequacy.hpp"

#include <gtest/gtest.h>

#include "circuit_networks.hpp"

#include <cmath>
#include <random>

using namespace piezo::dsp;

namespace {

using test_networks::branch;
using test_networks::kTwoPi;
using test_networks::tube_like;

struct Grid {
  Eigen::VectorXd f;
  Eigen::VectorXcd z;
};

// Z of c on a linear grid, times (1 + ripple·sin(2π f/period)) when asked, plus
// complex Gaussian noise of relative size noise_rel (noise_rel/√2 per component).
Grid sample(const EquivalentCircuit& c, double f0, double f1, double df, double noise_rel, unsigned seed,
            double ripple = 0, double period_hz = 1) {
  const auto n = static_cast<Eigen::Index>(std::floor((f1 - f0) / df)) + 1;
  Grid g{Eigen::VectorXd(n), Eigen::VectorXcd(n)};
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01;
  for (Eigen::Index i = 0; i < n; ++i) {
    g.f[i] = f0 + df * static_cast<double>(i);
    auto z = c.impedance(g.f[i]) * (1.0 + ripple * std::sin(kTwoPi * g.f[i] / period_hz));
    const double s = noise_rel * std::abs(z) / std::sqrt(2.0);
    g.z[i] = z + std::complex<double>(s * n01(rng), s * n01(rng));
  }
  return g;
}

}  // namespace

TEST(CircuitAdequacy, ScatterNoiseRecoversTheNoisePutIn) {
  // 1 % complex noise: 0.707 % per component of δZ/Z. The median of ~2900
  // |deviations| has a relative standard error of about 2.5 %; 10 % is 4σ.
  for (unsigned seed : {1u, 2u, 3u}) {
    const auto g = sample(tube_like(), 2e3, 150e3, 100, 0.01, seed);
    EXPECT_NEAR(scatter_noise_rel(g.f, g.z, false) / (0.01 / std::sqrt(2.0)), 1.0, 0.1) << seed;
  }
  // Noiseless data: the floor of an analyzer's printed digits, not zero.
  const auto clean = sample(tube_like(), 2e3, 150e3, 100, 0.0, 1);
  EXPECT_LT(scatter_noise_rel(clean.f, clean.z, false), 5e-4);  // the resonances' own curvature only
  EXPECT_GE(scatter_noise_rel(clean.f, clean.z, false), 1e-6);
}

TEST(CircuitAdequacy, ProminentPeaksAreTheModes) {
  const auto g = sample(tube_like(), 2e3, 150e3, 50, 0.002, 4);
  const double noise = scatter_noise_rel(g.f, g.z, false);
  const auto peaks = prominent_conductance_peaks(g.f, g.z, false, noise);
  ASSERT_EQ(peaks.size(), 3u);
  std::vector<double> fs;
  for (const auto& p : peaks) fs.push_back(p.f_hz);
  std::sort(fs.begin(), fs.end());
  const auto truth = tube_like();
  for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(fs[k], truth.branches[k].fs_hz(), 100.0) << k;
  // The most prominent first: the 52 kHz mode (the largest C1).
  EXPECT_NEAR(peaks.front().f_hz, 52e3, 100.0);
}

TEST(CircuitAdequacy, AGoodFitIsOkAndItsSigmasAreNotWidenedOnWhiteNoise) {
  const auto g = sample(tube_like(), 2e3, 150e3, 100, 0.005, 5);
  const auto fit = fit_equivalent_circuit(g.f, g.z, {});
  EXPECT_EQ(fit.status, "ok");
  ASSERT_EQ(fit.modes.size(), 3u);
  for (const auto& m : fit.modes) {
    EXPECT_EQ(m.status, "ok") << m.fs_hz.value << (m.reasons.empty() ? "" : m.reasons.front());
  }
  EXPECT_NEAR(fit.residual_to_scatter, 1.0, 0.15);
  ASSERT_EQ(fit.data_peaks.size(), 3u);
  for (const auto& p : fit.data_peaks) EXPECT_GE(p.mode, 0);
}

TEST(CircuitAdequacy, TheWrongModelIsUnreliableOrItsSigmaCoversTheError) {
  // A close pair fitted with ONE branch (--modes 1): the network cannot
  // describe the data. Every reported figure is either marked unreliable or
  // within 3σ of the nearer true mode.
  EquivalentCircuit truth;
  truth.c0_f = 4e-9;
  truth.tan_delta = 0.01;
  truth.branches = {branch(48.2e3, 40, 0.3e-9), branch(51.0e3, 40, 0.25e-9)};
  const auto g = sample(truth, 30e3, 70e3, 40, 0.002, 6);
  CircuitFitOptions opt;
  opt.max_branches = 1;
  const auto fit = fit_equivalent_circuit(g.f, g.z, {}, opt);
  ASSERT_GE(fit.modes.size(), 1u);
  for (const auto& m : fit.modes) {
    if (m.status != "ok") {
      EXPECT_FALSE(m.reasons.empty());
      continue;
    }
    double err = 1e300;
    for (const auto& b : truth.branches) err = std::min(err, std::abs(m.fs_hz.value - b.fs_hz()));
    EXPECT_LE(err, 3 * m.fs_hz.sigma) << m.fs_hz.value;
  }
  // And the data's second peak is named as having no mode.
  int unmatched = 0;
  for (const auto& p : fit.data_peaks) unmatched += p.mode < 0;
  EXPECT_GE(unmatched, 1);
}

TEST(CircuitAdequacy, StructuredResidualWidensSigmaToCoverTheBias) {
  // A 3 % ripple in Z with a period of 6 kHz (a cable or fixture resonance the
  // network lacks) on a 0.05 % noise floor: the residual is structure, not
  // noise. The strong mode's fs must stay within 3σ of the network's, with σ
  // widened (and a note saying why), or be marked unreliable.
  const auto truth = tube_like();
  const auto g = sample(truth, 2e3, 150e3, 50, 0.0005, 7, 0.03, 6e3);
  const auto fit = fit_equivalent_circuit(g.f, g.z, {});
  ASSERT_GE(fit.modes.size(), 1u);
  EXPECT_GT(fit.residual_to_scatter, 5.0);
  EXPECT_GT(fit.residual_lag1, 0.5);
  // The ripple's own conductance wiggles may come out as weak modes (the data
  // do show them); the three true modes are judged: each reported one nearest
  // a true branch is within 3σ of it, with σ widened and saying why, or is
  // marked unreliable.
  int judged = 0;
  for (const auto& b : truth.branches) {
    const CircuitModeFigures* near = nullptr;
    for (const auto& m : fit.modes)
      if (!near || std::abs(m.fs_hz.value - b.fs_hz()) < std::abs(near->fs_hz.value - b.fs_hz())) near = &m;
    ASSERT_NE(near, nullptr);
    if (std::abs(near->fs_hz.value - b.fs_hz()) > 0.05 * b.fs_hz()) continue;  // not found: nothing claimed
    ++judged;
    if (near->status != "ok") {
      EXPECT_FALSE(near->reasons.empty());
      continue;
    }
    EXPECT_LE(std::abs(near->fs_hz.value - b.fs_hz()), 3 * near->fs_hz.sigma) << b.fs_hz();
    EXPECT_FALSE(near->sigma_notes.empty()) << b.fs_hz();
  }
  EXPECT_GE(judged, 2);
}

TEST(CircuitAdequacy, ImplausibleFitsAreMarked) {
  // Constructed fits: a low-Q branch standing in for C0, a tan δ above 0.1 and
  // a k_eff above any material's.
  EquivalentCircuit c;
  c.c0_f = 1e-13;
  c.tan_delta = 0.3;
  c.branches = {branch(20e3, 0.5, 2e-9), branch(60e3, 50, 1e-9)};
  Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(400, 5e3, 100e3);
  Eigen::VectorXcd z(f.size());
  for (Eigen::Index i = 0; i < f.size(); ++i) z[i] = c.impedance(f[i]);
  CircuitFit fit;
  fit.circuit = c;
  fit.converged = true;
  fit.misfit_abs_rel_rms = 0;
  fit.modes = {circuit_mode_figures(c, 0), circuit_mode_figures(c, 1)};
  for (auto& m : fit.modes) {
    m.misfit_rel_rms = 0;
    for (const auto& [name, x] : named_figures(m)) x->sigma = 1e-3 * std::abs(x->value);
  }
  assess_circuit_fit(f, z, fit);
  EXPECT_EQ(fit.status, "inadequate");
  for (const auto& m : fit.modes) EXPECT_EQ(m.status, "unreliable");
  bool absorbed = false, tand = false, keff = false;
  for (const auto& r : fit.modes[1].reasons) {
    absorbed |= r.find("absorbed") != std::string::npos;
    tand |= r.find("tan d") != std::string::npos;
    keff |= r.find("k_eff") != std::string::npos;
  }
  EXPECT_TRUE(absorbed);
  EXPECT_TRUE(tand);
  EXPECT_TRUE(keff);  // C1/(C0 + C1) ≈ 1: k_eff ≈ 1
}

TEST(CircuitAdequacy, ALowQBranchNeverStandsInForC0) {
  // A thickness-mode disc's shape: one strong, broad mode above a large C0. The
  // fit's C0 stays the data's clamped capacitance (within 10 %), never a
  // picofarad beside a low-Q branch holding the nanofarads.
  EquivalentCircuit truth;
  truth.c0_f = 1.2e-9;
  truth.tan_delta = 0.02;
  truth.branches = {branch(2.1e6, 25, 0.4e-9)};
  Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(801, 0.5e6, 4e6);
  Grid g{f, Eigen::VectorXcd(f.size())};
  std::mt19937 rng(9);
  std::normal_distribution<double> n01;
  for (Eigen::Index i = 0; i < f.size(); ++i) {
    const auto z = truth.impedance(f[i]);
    g.z[i] = z + 0.003 * std::abs(z) * std::complex<double>(n01(rng), n01(rng));
  }
  const auto fit = fit_equivalent_circuit(g.f, g.z, {});
  EXPECT_NEAR(fit.circuit.c0_f / truth.c0_f, 1.0, 0.1);
  for (const auto& b : fit.circuit.branches) EXPECT_FALSE(b.qm() < 1.0 && b.c_f > fit.circuit.c0_f);
}
