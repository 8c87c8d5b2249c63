// Output-error fit of the modal port model (update/port_fit.hpp) against
// independent truths: a closed-form single branch, an exactly representable
// three-branch tube (recovered to round-off from a perturbed start), the full
// FE port model of the tube (24 modes + residual: the FE short-/open-circuit
// eigenfrequencies), and the spread over noise seeds vs the reported σ's.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "model/material_presets.hpp"
#include "model/transient.hpp"
#include "tests/support/tube_fixture.hpp"
#include "update/parametrization.hpp"
#include "update/port_fit.hpp"
#include "update/updater.hpp"

using namespace piezo;
using namespace piezo::update;

namespace {

constexpr double kFs = 1e7, kR1 = 3140.0, kDecay = 1e5;
constexpr int kSamples = 6000;

std::vector<double> drive() {  // 1 V exp_decay from t = 0 (the study's drive)
  std::vector<double> v(kSamples);
  for (int k = 0; k < kSamples; ++k) v[k] = std::exp(-kDecay * k / kFs);
  return v;
}

model::ModalPortModel scaled_damping(model::ModalPortModel p, double beta) {
  for (auto& m : p.modes) m.kappa *= beta;  // c_k = β κ_k in the fit's convention
  return p;
}

class PortFit : public test::TubeFixture {
 protected:
  static void SetUpTestSuite() {
    TubeFixture::SetUpTestSuite();
    const auto m = model::to_e_form(model::to_d_form(
        model::IsotropicPiezoParams{6.66e10, 0.3333, -210e-12, 2294 * model::kEps0}));
    model::ModalOptions o;
    o.n_modes = 24;  // as the simulated bench
    fe_port_ = std::make_unique<model::ModalPortModel>(solver_->port_model(m, o));
    const auto f = model_frequencies(*solver_, m, 3, 3, CmcmOptions{}.modal);
    sc_ = f.resonances_hz;
    oc_ = f.antiresonances_hz;
  }
  static void TearDownTestSuite() {
    fe_port_.reset();
    TubeFixture::TearDownTestSuite();
  }
  // Prony-like start: features off by a few 1e-3, 1 % damping.
  static PortFitStart start(const std::vector<double>& r, const std::vector<double>& a, double c) {
    PortFitStart s;
    for (std::size_t k = 0; k < r.size(); ++k) {
      s.resonances_hz.push_back(r[k] * (1 + 2e-3));
      s.antiresonances_hz.push_back(a[k] * (1 - 1e-3));
      s.damping_ratios.push_back(0.01);
    }
    s.capacitance_f = c * (1 + 1e-3);
    return s;
  }
  static inline std::unique_ptr<model::ModalPortModel> fe_port_;
  static inline std::vector<double> sc_, oc_;
};

}  // namespace

TEST(PortFitAlgebra, SingleBranchAntiResonanceIsClosedForm) {
  // C_e + q/(ω_r² − ω²) = 0  ⇔  ω_a² = ω_r² + q/C_e; with damping the zero of
  // C_e(s² + cs + ω_r²) + q has |s|² = ω_r² + q/C_e exactly as well.
  model::ModalPortModel p;
  p.c_clamped = 4e-9;
  model::PortMode m;
  m.omega = 2 * M_PI * 50e3;
  m.participation = std::sqrt(2e-10) * m.omega;  // q/ω² = 0.2 nF
  m.kappa = 2 * 0.02 * m.omega;                  // ζ = 2 %
  p.modes.push_back(m);
  const double want = std::sqrt(m.omega * m.omega + 2e-10 * m.omega * m.omega / 4e-9) / (2 * M_PI);
  EXPECT_NEAR(port_antiresonances_hz(p, false).at(0) / want, 1.0, 1e-12);
  EXPECT_NEAR(port_antiresonances_hz(p, true).at(0) / want, 1.0, 1e-10);
  EXPECT_NEAR(port_capacitance(p, 0.0), 4.2e-9, 1e-21);
}

TEST_F(PortFit, RepresentableTubeIsRecoveredExactly) {
  // Three in-band branches + static C_e, i.e. exactly the fitted model class
  // without the pseudo-mode: from a start 0.2 % off, the fit must land on the
  // truth to round-off (noise-free data).
  model::ModalPortModel truth;
  truth.c_clamped = fe_port_->c_clamped + fe_port_->c_residual;
  for (const auto& m : fe_port_->modes) {
    const double q = m.participation * m.participation;
    if (m.omega < 2 * M_PI * 120e3 && q / (m.omega * m.omega) > 1e-11)
      truth.modes.push_back(m);
    else
      truth.c_clamped += q / (m.omega * m.omega);
  }
  ASSERT_EQ(truth.modes.size(), 3u);
  const auto v1 = drive();
  const auto v2 = model::simulate_divider(truth, {0.0, 1e-7}, {.r1_ohm = kR1}, v1, kFs);
  const auto anti = port_antiresonances_hz(scaled_damping(truth, 1e-7), true);
  std::vector<double> res;
  for (const auto& m : truth.modes) res.push_back(m.omega / (2 * M_PI));
  PortFitOptions o;
  o.high_mode = false;
  const auto r =
      fit_port_model(v1, v2, kFs, kR1, start(res, anti, port_capacitance(truth, 400)), o);
  ASSERT_TRUE(r.converged) << r.message;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(r.features.resonances_hz[k] / res[k], 1.0, 1e-9) << k;
    EXPECT_NEAR(r.features.antiresonances_hz[k] / anti[k], 1.0, 1e-9) << k;
  }
  EXPECT_NEAR(r.features.low_frequency_capacitance() / port_capacitance(truth, 400), 1.0, 1e-9);
  EXPECT_LT(r.residual_rms_v, 1e-9);
}

TEST_F(PortFit, FullFeTubeGivesItsModalFrequencies) {
  // The simulated bench's tube (24 modes + residual mode, β = 1e-7 s) fitted
  // with three branches + C_e + one pseudo-mode. Budget: resonances within 1e-4
  // of the FE short-circuit frequencies; anti-resonances are |s*| of the damped
  // zeros of Q/V — for β K_UU damping the open-circuit modes are not
  // proportionally damped, so |s*| of the third sits +2.0e-4 above the undamped
  // FE open-circuit frequency (the same in the true port model, checked here);
  // the fit must reproduce the true port model's |s*| within 5e-5.
  const auto v1 = drive();
  const auto v2 = model::simulate_divider(*fe_port_, {0.0, 1e-7}, {.r1_ohm = kR1}, v1, kFs);
  // The true port model's damped anti-resonances next to the FE ones (it also
  // has those of the weak symmetric modes, e.g. 86.4 kHz).
  std::vector<double> anti_true;
  for (double f : oc_) {
    double best = 0;
    for (double a : port_antiresonances_hz(scaled_damping(*fe_port_, 1e-7), true))
      if (std::abs(a - f) < std::abs(best - f)) best = a;
    anti_true.push_back(best);
  }
  const double c400 = port_capacitance(*fe_port_, 400);
  const auto r = fit_port_model(v1, v2, kFs, kR1, start(sc_, oc_, c400));
  ASSERT_TRUE(r.converged) << r.message;
  for (int k = 0; k < 3; ++k) {
    const double er = r.features.resonances_hz[k] / sc_[k] - 1;
    const double ea = r.features.antiresonances_hz[k] / anti_true[k] - 1;
    std::printf(
        "mode %d: resonance %.2f Hz (FE %.2f, %+.1e); anti-resonance %.2f Hz (damped true %.2f, "
        "%+.1e; FE undamped %.2f)\n",
        k + 1, r.features.resonances_hz[k], sc_[k], er, r.features.antiresonances_hz[k],
        anti_true[k], ea, oc_[k]);
    EXPECT_LT(std::abs(er), 1e-4) << k;
    EXPECT_LT(std::abs(ea), 5e-5) << k;
    EXPECT_LT(std::abs(anti_true[k] / oc_[k] - 1), 2.5e-4) << k;
  }
  EXPECT_NEAR(r.features.low_frequency_capacitance() / c400, 1.0, 1e-4);
}

TEST_F(PortFit, ReportedSigmasMatchTheScatterOverNoiseSeeds) {
  // White noise of 2e-4 V on v2 (the level of 16 averaged 3 % shots with the
  // study's drive); 6 seeds. The Gauss–Newton σ's are used as weights of the
  // least-squares updater, so they must describe the scatter within a factor 3
  // either way (6 seeds estimate a σ to ±30 %). Measured ratios scatter/σ:
  // 0.36 (third resonance: its σ carries the pseudo-mode's correlations) to 1.3.
  const auto v1 = drive();
  const auto clean = model::simulate_divider(*fe_port_, {0.0, 1e-7}, {.r1_ohm = kR1}, v1, kFs);
  const double c400 = port_capacitance(*fe_port_, 400);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> nd(0.0, 2e-4);
  std::vector<std::vector<double>> vals(7);
  std::vector<double> sig(7, 0.0);
  const int seeds = 6;
  for (int s = 0; s < seeds; ++s) {
    auto v2 = clean;
    for (auto& x : v2) x += nd(rng);
    const auto r = fit_port_model(v1, v2, kFs, kR1, start(sc_, oc_, c400));
    ASSERT_TRUE(r.converged) << r.message;
    ASSERT_EQ(r.features.resonance_sigma_hz.size(), 3u);
    for (int k = 0; k < 3; ++k) {
      vals[k].push_back(r.features.resonances_hz[k]);
      vals[3 + k].push_back(r.features.antiresonances_hz[k]);
      sig[k] += r.features.resonance_sigma_hz[k] / seeds;
      sig[3 + k] += r.features.antiresonance_sigma_hz[k] / seeds;
    }
    vals[6].push_back(r.features.low_z_ohm);
    sig[6] += r.features.low_z_sigma_ohm / seeds;
  }
  for (int q = 0; q < 7; ++q) {
    double m = 0, v = 0;
    for (double x : vals[q]) m += x / seeds;
    for (double x : vals[q]) v += (x - m) * (x - m) / (seeds - 1);
    const double ratio = std::sqrt(v) / sig[q];
    std::printf("feature %d: scatter %.3g, reported sigma %.3g (ratio %.2f)\n", q, std::sqrt(v),
                sig[q], ratio);
    EXPECT_GT(ratio, 1 / 3.0) << q;
    EXPECT_LT(ratio, 3.0) << q;
  }
}

TEST(PortFitInput, BadInputIsRefused) {
  const std::vector<double> v(1000, 1.0), shorter(999, 1.0);
  PortFitStart s;
  s.resonances_hz = {50e3, 53e3};
  s.antiresonances_hz = {51e3, 54e3};
  s.capacitance_f = 1e-8;
  EXPECT_THROW(fit_port_model(v, shorter, kFs, kR1, s), std::invalid_argument);
  EXPECT_THROW(fit_port_model(v, v, kFs, -1.0, s), std::invalid_argument);
  PortFitStart crossed = s;
  crossed.antiresonances_hz = {54e3, 55e3};  // a1 above r2: not interlaced
  EXPECT_THROW(fit_port_model(v, v, kFs, kR1, crossed), std::invalid_argument);
  auto nan = v;
  nan[10] = std::nan("");
  EXPECT_THROW(fit_port_model(nan, v, kFs, kR1, s), std::invalid_argument);
  PortFitStart none;
  none.capacitance_f = 1e-8;
  EXPECT_THROW(fit_port_model(v, v, kFs, kR1, none), std::invalid_argument);
}
