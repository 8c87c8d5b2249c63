// Per-mode figures (dsp/mode_figures.hpp) against closed forms: an exact BVD
// network (tests/dsp/bvd_model) with known R, L, C, C0 — noise-free and with
// seeded complex noise of known σ — and the FE tube's modal data
// (ModalSolver::port_model: each mode is exactly a series branch
// L = 1/p², C = p²/ω², R = c/p² in parallel with everything else).
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <random>

#include "bvd_model.hpp"
#include "dsp/mode_figures.hpp"
#include "model/material_presets.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"
#include "tests/support/apc850_port.hpp"

namespace {
using namespace piezo;
using cd = std::complex<double>;
constexpr double kTwoPi = 2 * M_PI;

struct Grid {
  Eigen::VectorXd f;
  Eigen::VectorXcd z;
};

Grid sample(const bvd::Bvd& m, double f0, double f1, double step) {
  Grid g;
  g.f = dsp::make_grid(f0, f1, step);
  g.z.resize(g.f.size());
  for (Eigen::Index k = 0; k < g.f.size(); ++k) g.z[k] = m.impedance_at(g.f[k]);
  return g;
}

double rel(double a, double b) { return std::abs(a / b - 1); }

// Noise-free: the fit's model is the network's, so the parameters are recovered to the
// LM's convergence (ln-step < 1e-13) and the conditioning of the window; 1e-6 relative
// leaves room for the Gauss–Seidel sweeps' tolerance (1e-9) times the modes' overlap.
void expect_branches(const dsp::ModeFiguresResult& r, const bvd::Bvd& m, double tol) {
  ASSERT_EQ(r.modes.size(), m.branches.size());
  for (std::size_t k = 0; k < m.branches.size(); ++k) {
    const auto& b = m.branches[k];
    const auto& x = r.modes[k];
    SCOPED_TRACE("mode " + std::to_string(k));
    const double fs = 1 / (kTwoPi * std::sqrt(b.L * b.C));
    const double q = 1 / (kTwoPi * fs * b.R * b.C);
    const double fp = fs * std::sqrt(1 + b.C / m.c0);
    std::printf(
        "mode %zu: R1 %.6f / %.6f ohm, L1 %.8g / %.8g H, C1 %.8g / %.8g F, C0 %.8g / %.8g F\n"
        "        fs %.6f / %.6f Hz, fp %.6f / %.6f Hz, Qm branch %.6f, bandwidth %.6f / %.6f, "
        "sweeps %d\n",
        k, x.r1_ohm.value, b.R, x.l1_h.value, b.L, x.c1_f.value, b.C, x.c0_f.value, m.c0,
        x.fs_hz.value, fs, x.fp_hz.value, fp, x.qm_branch.value, x.qm_bandwidth.value, q, r.sweeps);
    EXPECT_LT(rel(x.r1_ohm.value, b.R), tol);
    EXPECT_LT(rel(x.l1_h.value, b.L), tol);
    EXPECT_LT(rel(x.c1_f.value, b.C), tol);
    EXPECT_LT(rel(x.c0_f.value, m.c0), tol);
    EXPECT_LT(rel(x.fs_hz.value, fs), tol);
    EXPECT_LT(rel(x.fp_hz.value, fp), tol);
    EXPECT_LT(rel(x.k_eff2.value, (fp * fp - fs * fs) / (fp * fp)), tol);
    EXPECT_LT(rel(x.qm_branch.value, q), tol);
    // The bandwidth method uses the exact resonance form (conductance_peak.hpp) on the
    // conductance with the other fitted branches removed: exact up to those branches' error.
    EXPECT_LT(rel(x.qm_bandwidth.value, q), tol);
    EXPECT_LT(rel(x.conductance.fs_hz, fs), tol);
    EXPECT_TRUE(x.fit.converged) << x.fit.message;
  }
}

TEST(ModeFigures, SingleBranchNoiseFreeIsExact) {
  // fs 50 kHz, fp 52 kHz (lossless tuning), Q = 200, C0 = 2.5 nF.
  const auto m = bvd::make_bvd({50e3}, {52e3}, 2.5e-9, {1.0 / 400});
  const auto g = sample(m, 1e3, 120e3, 50);
  dsp::ModeFigureOptions o;
  o.mean_diameter_m = 0.0175;
  const auto r = dsp::mode_figures(g.f, g.z, {}, o);
  expect_branches(r, m, 1e-6);
  // k_eff² = (fp² − fs²)/fp² with the tuned fp = 52 kHz exactly (make_bvd).
  EXPECT_NEAR(r.modes[0].k_eff2.value, 1 - std::pow(50.0 / 52.0, 2), 1e-9);
  // C^T and tan δ at 1 kHz: the network's Y(j2π·1 kHz) (a grid point: no interpolation).
  const cd y = m.admittance(cd(0, kTwoPi * 1e3));
  EXPECT_EQ(r.reference_used_hz, 1e3);
  EXPECT_LT(rel(r.free_capacitance_f.value, y.imag() / (kTwoPi * 1e3)), 1e-12);
  EXPECT_LT(rel(r.tan_delta.value, y.real() / y.imag()), 1e-9);
  EXPECT_EQ(r.hoop_mode, 0);
  EXPECT_LT(rel(r.frequency_constant_hz_m.value, 50e3 * 0.0175), 1e-6);
}

TEST(ModeFigures, ThreeBranchTubeNetworkNoiseFree) {
  // The estimator tests' tube-like network: the close pair 50.3/51.1 and 53.4/54.0 kHz
  // overlaps, which only the other modes' subtraction takes apart.
  const auto m = bvd::tube_bvd_q(150);
  const auto g = sample(m, 1e3, 120e3, 50);
  const auto r = dsp::mode_figures(g.f, g.z, {});
  expect_branches(r, m, 1e-6);
  // Without the subtraction each mode's C0 absorbs its neighbour's tail: a bias that
  // is the point of subtracting (printed, and bounded loosely to show it is there).
  dsp::ModeFigureOptions iso;
  iso.subtract_other_modes = false;
  const auto ri = dsp::mode_figures(g.f, g.z, {}, iso);
  ASSERT_EQ(ri.modes.size(), 3u);
  const double fs0 = 1 / (kTwoPi * std::sqrt(m.branches[0].L * m.branches[0].C));
  std::printf("isolated fits: mode 1 fs %+.2e, C0 %+.2e relative\n",
              ri.modes[0].fs_hz.value / fs0 - 1, ri.modes[0].c0_f.value / m.c0 - 1);
  EXPECT_GT(std::abs(ri.modes[0].c0_f.value / m.c0 - 1), 1e-3);
}

// Work proportional to the grid (issue 16): a long noisy record's FFT ratio has
// thousands of |Z| minima up high (2834 on a 1e6-sample simulated shot, where
// fitting them all did not finish in 10 min). Here the tube network's three modes
// below 120 kHz, then 1000 spurious dips of 1 dB on a 1 Hz-step grid to 2 MHz:
// the lowest max_modes are fitted, the note says how many were left, and the
// three real modes come out as on the clean grid.
TEST(ModeFigures, ManySpuriousMinimaAreCappedAndTheRealModesStand) {
  const auto m = bvd::tube_bvd_q(150);
  auto g = sample(m, 1e3, 2e6, 1);
  for (Eigen::Index k = 0; k < g.f.size(); ++k)
    if (g.f[k] > 150e3) g.z[k] *= 1.0 - 0.06 * std::pow(std::cos(kTwoPi * g.f[k] / 1850.0), 8);
  dsp::ModeFigureOptions o;
  o.max_modes = 8;
  const auto r = dsp::mode_figures(g.f, g.z, {}, o);
  ASSERT_EQ(r.modes.size(), 8u);
  bool noted = false;
  for (const auto& n : r.notes) noted |= n.find("minima on the grid: the lowest 8 fitted") != std::string::npos;
  EXPECT_TRUE(noted);
  const auto clean = sample(m, 1e3, 150e3, 1);
  const auto rc = dsp::mode_figures(clean.f, clean.z, {});
  ASSERT_GE(rc.modes.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(r.modes[k].fs_hz.value / rc.modes[k].fs_hz.value, 1.0, 1e-6) << k;
    // k_eff² of the top real mode moves by 0.24 %: the spurious dips above it are
    // fitted as branches too and their tails enter its background (as any mode's would).
    EXPECT_NEAR(r.modes[k].k_eff2.value / rc.modes[k].k_eff2.value, 1.0, 1e-2) << k;
  }
}

TEST(ModeFigures, LowReferenceFrequencyIsNoted) {
  const auto m = bvd::tube_bvd_q(150);
  const auto g = sample(m, 2e3, 120e3, 50);
  const auto r = dsp::mode_figures(g.f, g.z, {});
  EXPECT_EQ(r.reference_used_hz, 2e3);
  ASSERT_FALSE(r.notes.empty());
  EXPECT_NE(r.notes[0].find("lowest"), std::string::npos);
}

// Complex Gaussian noise of σ_k = level·|Z_k| per point (E|δZ|² = σ_k²), given to the fit.
Grid noisy(const Grid& clean, double level, std::uint64_t seed, Eigen::VectorXd& sigma) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> nd(0, 1);
  Grid g = clean;
  sigma.resize(g.f.size());
  for (Eigen::Index k = 0; k < g.f.size(); ++k) {
    sigma[k] = level * std::abs(clean.z[k]);
    g.z[k] += sigma[k] / std::sqrt(2.0) * cd(nd(rng), nd(rng));
  }
  return g;
}

TEST(ModeFigures, SeededNoiseWithinThreeSigmaAndSigmasCalibrated) {
  const auto m = bvd::tube_bvd_q(150);
  const auto clean = sample(m, 1e3, 120e3, 50);
  // One seed: every figure within 3σ of the truth (4 parameters × 3 modes).
  // Over 40 seeds: the normalised errors (err/σ) of all of them have an rms near 1 —
  // the σ from the Jacobian are the scatter, not just a bound. 480 samples: the rms
  // of a unit normal estimates to ±3.2 % (1σ); 0.8–1.25 allows for the fit's
  // nonlinearity at 0.5 % noise.
  double s2 = 0;
  int n = 0, outside = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    Eigen::VectorXd sigma;
    const auto g = noisy(clean, 0.005, seed, sigma);
    const auto r = dsp::mode_figures(g.f, g.z, sigma);
    ASSERT_EQ(r.modes.size(), 3u) << "seed " << seed;
    for (std::size_t k = 0; k < 3; ++k) {
      const auto& b = m.branches[k];
      const auto& x = r.modes[k];
      const double e[4] = {(x.r1_ohm.value - b.R) / x.r1_ohm.sigma,
                           (x.l1_h.value - b.L) / x.l1_h.sigma, (x.c1_f.value - b.C) / x.c1_f.sigma,
                           (x.c0_f.value - m.c0) / x.c0_f.sigma};
      for (double v : e) {
        s2 += v * v;
        ++n;
        outside += std::abs(v) > 3;
        if (seed == 1) {
          EXPECT_LT(std::abs(v), 3.0) << "mode " << k;
        }
      }
      if (seed == 1) {
        std::printf(
            "seed 1 mode %zu: R1 %.4f ± %.4f (true %.4f), L1 %.6g ± %.2g (%.6g), C1 %.6g ± %.2g "
            "(%.6g), "
            "C0 %.6g ± %.2g (%.6g), Qm %.2f ± %.2f / bandwidth %.2f ± %.2f, chi2/dof %.3f\n",
            k, x.r1_ohm.value, x.r1_ohm.sigma, b.R, x.l1_h.value, x.l1_h.sigma, b.L, x.c1_f.value,
            x.c1_f.sigma, b.C, x.c0_f.value, x.c0_f.sigma, m.c0, x.qm_branch.value,
            x.qm_branch.sigma, x.qm_bandwidth.value, x.qm_bandwidth.sigma, x.fit.chi2_per_dof);
        // Qm both ways agree within 3 combined σ (they share data, so this is loose).
        EXPECT_LT(std::abs(x.qm_bandwidth.value - x.qm_branch.value),
                  3 * std::hypot(x.qm_bandwidth.sigma, x.qm_branch.sigma));
        EXPECT_NEAR(x.fit.chi2_per_dof, 1.0, 0.2);  // ~500 points per window: ±0.05 (1σ)
      }
    }
  }
  const double rms = std::sqrt(s2 / n);
  std::printf("40 seeds, %d normalised errors: rms %.3f, |err| > 3 sigma: %d\n", n, rms, outside);
  EXPECT_GT(rms, 0.8);
  EXPECT_LT(rms, 1.25);
  EXPECT_LE(outside, 4);  // expected 0.27 % of 480 = 1.3
}

TEST(ModeFigures, WithoutSigmaTheResidualSetsTheUncertainty) {
  const auto m = bvd::tube_bvd_q(150);
  Eigen::VectorXd sigma;
  const auto g = noisy(sample(m, 1e3, 120e3, 50), 0.005, 7, sigma);
  const auto r = dsp::mode_figures(g.f, g.z, {});
  ASSERT_EQ(r.modes.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    const auto& b = m.branches[k];
    const auto& x = r.modes[k];
    EXPECT_FALSE(x.fit.weighted);
    // Relative weights are the right ones for this noise (σ ∝ |Z|), so the residual-scaled
    // σ equal the weighted fit's: 3σ holds as above.
    EXPECT_LT(std::abs(x.r1_ohm.value - b.R), 3 * x.r1_ohm.sigma) << k;
    EXPECT_LT(std::abs(x.c1_f.value - b.C), 3 * x.c1_f.sigma) << k;
    EXPECT_LT(std::abs(x.c0_f.value - m.c0), 3 * x.c0_f.sigma) << k;
    EXPECT_TRUE(std::isnan(x.qm_bandwidth.sigma));
  }
}

TEST(ModeFigures, BadInputThrows) {
  Eigen::VectorXd f = dsp::make_grid(1e3, 2e3, 100);
  Eigen::VectorXcd z = Eigen::VectorXcd::Ones(f.size() - 1);
  EXPECT_THROW(dsp::mode_figures(f, z, {}), std::invalid_argument);
  Eigen::VectorXcd y = Eigen::VectorXcd::Ones(2);
  EXPECT_THROW(dsp::fit_admittance_circle(y), std::invalid_argument);
}

// ---- the FE tube (APC850, the published geometry, 24 modes + residual) ----

struct FePort {
  model::ModalPortModel port;
  model::RayleighDamping damping;
};

using test::apc850_port;

struct FeTol {
  double fs, k2, c1;
};

void fe_case(double beta, FeTol tol) {
  std::vector<double> fit_q;
  std::vector<std::size_t> notes;
  const auto& port = apc850_port();
  const model::RayleighDamping d{0.0, beta};
  const Eigen::VectorXd f = dsp::make_grid(1e3, 120e3, 10);
  Eigen::VectorXcd z(f.size());
  for (Eigen::Index k = 0; k < f.size(); ++k) {
    const double w = kTwoPi * f[k];
    z[k] = 1.0 / (cd(0, w) * port.charge_per_volt(w, d));
  }
  model::TubeGeometry g;
  dsp::ModeFigureOptions o;
  o.mean_diameter_m = 0.5 * (g.inner_diameter_m + g.outer_diameter_m);
  const auto r = dsp::mode_figures(f, z, {}, o);
  // Active modes: symmetric, coupling p²/(ω²C0) > 1e-3 (ModalOptions), in band.
  std::vector<const model::PortMode*> active;
  for (const auto& m : port.modes) {
    const double km2 = m.participation * m.participation / (m.omega * m.omega * port.c_clamped);
    if (!m.residual && m.symmetric && km2 > 1e-3 && m.omega / kTwoPi < 120e3) active.push_back(&m);
  }
  ASSERT_EQ(active.size(), 3u);
  ASSERT_EQ(r.modes.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    const auto& m = *active[k];
    const auto& x = r.modes[k];
    const double p2 = m.participation * m.participation, w2 = m.omega * m.omega;
    const double f_modal = m.omega / kTwoPi, c1 = p2 / w2, l1 = 1 / p2,
                 r1 = (d.alpha + d.beta * m.kappa) / p2;
    const double km2 = c1 / port.c_clamped;
    // The shunt the mode sees: C0, the residual capacitance and every mode the figures
    // did not fit (the weak symmetric and the antisymmetric-by-symmetry ones carry none,
    // the modes above the band and the residual mode most) — frequency dependent, so
    // k_eff² = C1/(C_bg + C1) is defined only as well as C_bg is constant between fs and fp.
    auto c_bg = [&](double ff) {
      const double w = kTwoPi * ff;
      cd c = port.c_clamped + port.c_residual;
      for (const auto& o : port.modes) {
        bool fitted = false;
        for (const auto* a : active) fitted = fitted || a == &o;
        if (!fitted)
          c += o.participation * o.participation /
               cd(o.omega * o.omega - w * w, w * (d.alpha + d.beta * o.kappa));
      }
      return c.real();
    };
    const double cs = c_bg(f_modal), cp = c_bg(x.fp_hz.value);
    const double k2s = c1 / (cs + c1), k2p = c1 / (cp + c1);
    std::printf(
        "beta %.0e mode %zu: fs %.3f Hz (modal %.3f, %+.2e), fm %.3f, fp %.3f, fn %.3f\n"
        "   C1 %+.2e, L1 %+.2e, R1 %+.2e relative to p^2/w^2, 1/p^2, c/p^2; C0 fit %.5g F "
        "(C_bg at fs %.5g, at fp %.5g; C0 clamped %.5g)\n"
        "   k_eff^2 %.6f: C1/(C_bg+C1) %.6f..%.6f; modal coupling p^2/(w^2 C0) %.6f -> "
        "km2/(1+km2) %.6f; Qm %.2f / bandwidth %.2f (c/p^2 branch: %.2f); N %.2f Hz m\n",
        beta, k, x.fs_hz.value, f_modal, x.fs_hz.value / f_modal - 1, x.fm_hz.value, x.fp_hz.value,
        x.fn_hz.value, x.c1_f.value / c1 - 1, x.l1_h.value / l1 - 1, x.r1_ohm.value / r1 - 1,
        x.c0_f.value, cs, cp, port.c_clamped, x.k_eff2.value, std::min(k2s, k2p),
        std::max(k2s, k2p), km2, km2 / (1 + km2), x.qm_branch.value, x.qm_bandwidth.value,
        1 / (m.omega * r1 * c1), x.frequency_constant_hz_m.value);
    // fs is the series resonance of the mode's branch — the modal frequency by construction
    // (X1 = ωL1 − 1/(ωC1) = 0 at ω_k, for any damping). What the one-branch fit cannot
    // represent moves it: the symmetric mode at 83.9 kHz (coupling 2e-4, no |Z| extremum,
    // so not fitted) inside mode 3's window, and at the seed's damping (Q ≈ 20–30) the
    // close pair's overlap. Measured: β = 1e-8: −2.2e-7, −2.6e-7, −1.1e-5;
    // β = 1e-7: −3.1e-5, +7.4e-6, −1.0e-4.
    EXPECT_LT(rel(x.fs_hz.value, f_modal), tol.fs) << k;
    // k_eff² = (fp² − fs²)/fp² = C1/(C0 + C1) of the fit against the same definition with
    // the shunt the mode actually sees (bracketed by its values at fs and fp). The modal
    // coupling p²/(ω²C0) is referred to the clamped C0 = 3.48 nF; the shunt includes the
    // 3.27 nF of the modes above the band, so k_eff² = k_m²/(C_bg/C0 + k_m²) ≈ k_m²/2 here.
    // The residual difference is the fitted C1 (mode 3's +1 % error, from the 83.9 kHz
    // mode, enters modes 1–2 through their background): measured ≤ 0.8 % (β = 1e-8),
    // ≤ 5.2 % (β = 1e-7: the pair's overlap).
    EXPECT_GT(x.k_eff2.value, std::min(k2s, k2p) * (1 - tol.k2)) << k;
    EXPECT_LT(x.k_eff2.value, std::max(k2s, k2p) * (1 + tol.k2)) << k;
    EXPECT_LT(rel(x.c1_f.value, c1), tol.c1) << k;
    // The bandwidth Qm reads the conductance alone, which the weak mode barely touches:
    // within 1e-3 of the branch's 1/(ω_k R C) at β = 1e-8 (measured ≤ 2.5e-4).
    if (beta < 5e-8) {
      EXPECT_LT(rel(x.qm_bandwidth.value, 1 / (m.omega * r1 * c1)), 1e-3) << k;
    }
    fit_q.push_back(x.qm_branch.value);
    notes.push_back(x.notes.size());
  }
  if (beta < 5e-8) {
    // Mode 3's fitted Qm is pulled 10 % low by the 83.9 kHz mode; the two Qm disagree and
    // the figures say so — the cross-check doing its job.
    EXPECT_GT(notes[2], 0u);
    EXPECT_LT(fit_q[2], 0.95 * r.modes[2].qm_bandwidth.value);
  }
}

TEST(ModeFigures, FeTubeLightDamping) { fe_case(1e-8, {3e-5, 1e-2, 1.5e-2}); }
TEST(ModeFigures, FeTubeSeedDamping) { fe_case(1e-7, {2e-4, 6e-2, 5e-2}); }

}  // namespace
