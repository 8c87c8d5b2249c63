// update/model_figures (issue 34 item 3): the updated FE model's per-mode
// figures from its port model as a BVD network, checked against a second
// method — the FE's own short- and open-circuit modal solves — and the σ
// propagation against direct evaluations at the constants ± σ.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "model/material_presets.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"
#include "update/model_figures.hpp"

namespace {
using namespace piezo;

struct Fixture {
  model::TubeModel tube{model::TubeGeometry{}};
  model::ModalSolver solver{tube};
  update::MaterialClass cls = update::MaterialClass::isotropic();
  update::TubeParams p = model::isotropic_params(model::resolve_material({"apc850", true, ""}).d);
  update::OeLoss loss{update::OeDamping::rayleigh, 1e-7, 0};
  model::ModalOptions modal = update::OeOptions{}.modal;
};

TEST(ModelFigures, FsAndFpAreTheShortAndOpenCircuitModes) {
  Fixture fx;
  const auto mf = update::model_figures(fx.solver, fx.cls, fx.p, fx.loss, {}, 0, 130e3, fx.modal);
  ASSERT_GE(mf.modes.size(), 3u);
  const auto mat = fx.cls.e_form(fx.p);
  model::ModalOptions mo = fx.modal;
  mo.n_modes = 24;
  const auto sc = fx.solver.solve(mat, model::Electrodes::short_circuit, mo);
  const auto oc = fx.solver.solve(mat, model::Electrodes::open_circuit, mo);
  ASSERT_TRUE(sc.converged && oc.converged);
  auto nearest = [](const model::ModalResult& r, double f) {
    double best = 0;
    for (const auto& m : r.modes)
      if (m.symmetric_fraction > 0.5 && std::abs(m.frequency_hz - f) < std::abs(best - f)) best = m.frequency_hz;
    return best;
  };
  int strong = 0;
  for (const auto& m : mf.modes) {
    // fs: the short-circuit mode itself (the same eigenproblem).
    EXPECT_NEAR(m.fs_hz.value / nearest(sc, m.fs_hz.value), 1.0, 1e-6) << m.fs_hz.value;
    if (!std::isfinite(m.fp_hz.value)) continue;
    // fp: the zero of the network's susceptance against the open-circuit
    // solve. The network leaves the inactive modes' resonances out (their
    // static share stays in C0) and truncates above the computed modes (one
    // residual pseudo-mode): 0.1 % covers what that moves a mode with k_eff
    // above 0.1 (the zero moves by about the neglected susceptance over the
    // slope 2·C_k/ω·(ω/Δω)², a few 1e-4 at most here).
    if (m.k_eff_ieee176.value > 0.1) {
      EXPECT_NEAR(m.fp_hz.value / nearest(oc, m.fp_hz.value), 1.0, 1e-3) << "fs " << m.fs_hz.value;
      ++strong;
    }
    EXPECT_GT(m.fp_hz.value, m.fs_hz.value);
  }
  EXPECT_GE(strong, 2);
  // C^T: the static capacitance; C0 below it by the modes' static shares.
  EXPECT_NEAR(mf.free_capacitance_f.value / fx.solver.static_capacitance(mat), 1.0, 1e-9);
  EXPECT_LT(mf.c0_f.value, mf.free_capacitance_f.value);
  EXPECT_TRUE(std::isnan(mf.modes[0].fs_hz.sigma));  // no covariance: no σ
}

TEST(ModelFigures, SigmaIsTheSpreadAtThePlusMinusOneSigmaConstants) {
  Fixture fx;
  // 1 % on YE11 and 2 % on d31, fully correlated: one principal axis.
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(5, 5);
  const double s0 = 0.01, s2 = 0.02;
  cov(0, 0) = s0 * s0;
  cov(2, 2) = s2 * s2;
  cov(0, 2) = cov(2, 0) = s0 * s2;
  const auto mf = update::model_figures(fx.solver, fx.cls, fx.p, fx.loss, cov, 0, 130e3, fx.modal);
  EXPECT_EQ(mf.port_models, 3);  // the answer and ±1σ along the one axis
  auto at = [&](double k) {
    update::TubeParams q = fx.p;
    q.y_e11 *= std::exp(k * s0);
    q.d31 *= std::exp(k * s2);
    return update::model_figures(fx.solver, fx.cls, q, fx.loss, {}, 0, 130e3, fx.modal);
  };
  const auto plus = at(1), minus = at(-1);
  ASSERT_EQ(plus.modes.size(), mf.modes.size());
  ASSERT_EQ(minus.modes.size(), mf.modes.size());
  for (std::size_t i = 0; i < mf.modes.size(); ++i) {
    const auto& m = mf.modes[i];
    EXPECT_NEAR(m.fs_hz.sigma, 0.5 * std::abs(plus.modes[i].fs_hz.value - minus.modes[i].fs_hz.value),
                1e-9 * m.fs_hz.value);
    if (std::isfinite(m.k_eff_ieee176.value)) {
      EXPECT_NEAR(m.k_eff_ieee176.sigma,
                  0.5 * std::abs(plus.modes[i].k_eff_ieee176.value - minus.modes[i].k_eff_ieee176.value), 1e-12);
    }
    // fs ∝ √YE11 to first order (the piezoelectric stiffening moves with d31
    // and YE11 too, by the mode's k² at most): σ_fs/fs within 0.5 % ± k².
    const double k2 = std::pow(m.k_eff_ieee176.value, 2);
    if (std::isfinite(k2)) {
      EXPECT_NEAR(m.fs_hz.sigma / m.fs_hz.value, 0.5 * s0, 0.5 * s0 * k2 + 2 * s2 * k2);
    }
  }
}

TEST(ModelFigures, AWeakModeInsideAStrongOnesIntervalDoesNotTakeItsFp) {
  // Two branches: a strong one at 80 kHz (C1/C0 = 0.3, one-branch fp
  // 80·√1.3 = 91.2 kHz) and a weak one at 85 kHz inside that interval.
  dsp::EquivalentCircuit c;
  c.c0_f = 7e-9;
  auto branch = [](double fs, double cf, double q) {
    dsp::CircuitBranch b;
    b.c_f = cf;
    b.l_h = 1.0 / (std::pow(2 * std::numbers::pi * fs, 2) * cf);
    b.r_ohm = 2 * std::numbers::pi * fs * b.l_h / q;
    return b;
  };
  c.branches = {branch(80e3, 0.3 * 7e-9, 30), branch(85e3, 0.002 * 7e-9, 30)};
  const auto strong = dsp::circuit_mode_figures(c, 0), weak = dsp::circuit_mode_figures(c, 1);
  // The strong mode's fp with the weak branch as its static capacitance:
  // fs·√(1 + C1/(C0 + C2)).
  EXPECT_NEAR(strong.fp_hz.value, 80e3 * std::sqrt(1 + 0.3 / 1.002), 1.0);
  EXPECT_TRUE(std::isnan(weak.fp_hz.value));
  EXPECT_TRUE(std::isnan(weak.k_eff_ieee176.value));
  EXPECT_NEAR(weak.fs_hz.value, 85e3, 1e-6);
}

}  // namespace
