// End-face mass loading (model/end_mass.hpp) against truths that do not use
// its code: rigid-body kinetic mass and the radial moment of the face mass
// (closed-form integrals), first-order eigenvalue perturbation theory, the
// Courant–Fischer monotonicity of eigenvalues in M, and the direct harmonic
// solve of the loaded system against the loaded modal port model.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "model/end_mass.hpp"
#include "model/harmonic.hpp"
#include "model/material_presets.hpp"
#include "model/modal.hpp"
#include "tests/support/tube_fixture.hpp"

using namespace piezo;
using namespace piezo::model;

namespace {

PiezoMaterialE apc850() { return to_e_form(find_preset("apc850").material); }

class EndMass : public test::TubeFixture {
 protected:
  // Nodal field with u_r = fr(r, z), u_z = fz(r, z).
  template <class Fr, class Fz>
  Eigen::VectorXd field(Fr fr, Fz fz) const {
    Eigen::VectorXd u = Eigen::VectorXd::Zero(tube_->n_u());
    for (int n = 0; n < tube_->mesh().num_nodes(); ++n) {
      const auto& x = tube_->mesh().nodes()[n];
      u[tube_->dofs().u_r(n)] = fr(x.r, x.z);
      u[tube_->dofs().u_z(n)] = fz(x.r, x.z);
    }
    return u;
  }
  static double volume() {
    const TubeGeometry g;
    return M_PI * (g.outer_radius() * g.outer_radius() - g.inner_radius() * g.inner_radius()) *
           g.length_m;
  }
};

}  // namespace

TEST_F(EndMass, RigidTranslationCarriesTubePlusAddedMass) {
  const double rho_v = TubeGeometry{}.density_kg_m3 * volume();
  EXPECT_NEAR(tube_->tube_mass(), rho_v, 1e-14 * rho_v);
  const auto one = [](double, double) { return 1.0; };
  const auto zero = [](double, double) { return 0.0; };
  const Eigen::VectorXd uz = field(zero, one), ur = field(one, zero);
  for (double f : {0.0, 0.02, 0.3}) {
    const SpMat m = tube_->mass(f);
    // Exact integration (3-point Gauss on straight Q2 edges/elements): round-off only.
    EXPECT_NEAR(uz.dot(m * uz), (1 + f) * rho_v, 1e-12 * rho_v) << f;
    EXPECT_NEAR(ur.dot(m * ur), (1 + f) * rho_v, 1e-12 * rho_v) << f;  // u_r weighted the same
    EXPECT_NEAR(uz.dot(m * ur), 0.0, 1e-15 * rho_v) << f;              // no u_r–u_z coupling
  }
}

TEST_F(EndMass, HalfOnEachFaceSpreadInProportionToArea) {
  const TubeGeometry g;
  const double ri = g.inner_radius(), ro = g.outer_radius(), len = g.length_m;
  const SpMat& dm = tube_->split().m_end;  // f = 1
  const double m_tube = tube_->tube_mass();
  const auto zero = [](double, double) { return 0.0; };
  const auto one = [](double, double) { return 1.0; };
  const auto top = [&](double, double z) { return z > 0.5 * len - 1e-12 ? 1.0 : 0.0; };
  const auto interior = [&](double, double z) {
    return std::abs(z) < 0.5 * len - 1e-12 ? 1.0 : 0.0;
  };
  const Eigen::VectorXd all = field(zero, one);
  // Only the end-face nodes carry ΔM, half of it on each face.
  EXPECT_NEAR(all.dot(dm * field(zero, top)), 0.5 * m_tube, 1e-12 * m_tube);
  EXPECT_NEAR(field(zero, interior).dot(dm * field(zero, interior)), 0.0, 1e-15 * m_tube);
  // Radial moment ∫ r dm = 2 · (m/2)/(π(ro² − ri²)) · 2π(ro³ − ri³)/3: r is in the
  // quadratic edge space, so the consistent matrix gives it exactly. A mass spread
  // per unit length of the edge (no 2πr weight) would give m(ro + ri)/2 instead.
  const double want = m_tube * 2.0 * (ro * ro * ro - ri * ri * ri) / (3.0 * (ro * ro - ri * ri));
  EXPECT_NEAR(all.dot(dm * field(zero, [](double r, double) { return r; })), want, 1e-12 * want);
  EXPECT_GT(std::abs(want - m_tube * 0.5 * (ro + ri)),
            1e-6 * want);  // the check can tell the two apart
}

TEST_F(EndMass, FirstOrderPerturbationPredictsTheShift) {
  // K φ = λ(M + fΔM) φ: dλ/df = −λ φᵀΔMφ (φᵀMφ = 1), so δω/ω = −½ f φᵀΔMφ + O(f²).
  // At f = 1e-3 the O(f²) part is 0.1-1 % of the shift here (modes 1-2 of the
  // tube veer towards each other under end mass, λ/(λ2 − λ1) ≈ 8), so the
  // re-solved shifts at f and 2f are Richardson-extrapolated to their linear
  // part, (4δ(f) − δ(2f))/2 = a·f + O(f³), which must match to 1e-3 of the shift.
  const double f = 1e-3;
  ModalOptions o;
  o.n_modes = 10;
  const auto m = apc850();
  for (Electrodes el : {Electrodes::short_circuit, Electrodes::open_circuit}) {
    const auto base = solver_->solve(m, el, o);
    ModalOptions o1 = o, o2 = o;
    o1.end_mass_fraction = f;
    o2.end_mass_fraction = 2 * f;
    const auto r1 = solver_->solve(m, el, o1);
    const auto r2 = solver_->solve(m, el, o2);
    ASSERT_TRUE(base.converged && r1.converged && r2.converged);
    EXPECT_EQ(r1.end_mass_fraction, f);
    for (std::size_t k = 1; k < base.modes.size(); ++k) {  // k = 0: rigid translation
      const Eigen::VectorXd phi = base.shapes.col(static_cast<Eigen::Index>(k));
      const double predicted = -0.5 * f * phi.dot(tube_->split().m_end * phi);
      const double d1 = r1.modes[k].omega / base.modes[k].omega - 1.0;
      const double d2 = r2.modes[k].omega / base.modes[k].omega - 1.0;
      const double linear = 0.5 * (4.0 * d1 - d2);
      std::printf(
          "%s mode %zu: %.2f Hz, shift at f = 1e-3 %+.4e, predicted %+.4e "
          "(rel. diff %.1e; extrapolated linear part %.1e)\n",
          to_string(el), k, base.modes[k].frequency_hz, d1, predicted, std::abs(d1 / predicted - 1),
          std::abs(linear / predicted - 1));
      ASSERT_LT(predicted, 0.0);
      EXPECT_LT(std::abs(linear - predicted), 1e-3 * std::abs(predicted)) << k;
      EXPECT_LT(std::abs(d1 - predicted), 2e-2 * std::abs(predicted)) << k;  // O(f) second order
    }
  }
}

TEST_F(EndMass, FrequenciesDecreaseMonotonicallyWithTheFraction) {
  // Adding a positive semidefinite ΔM lowers every eigenvalue (Courant–Fischer);
  // with the mass on the vibrating faces, every elastic mode here strictly.
  ModalOptions o;
  o.n_modes = 10;
  const auto m = apc850();
  std::vector<double> prev;
  std::vector<double> prev_active;
  for (double f : {0.0, 0.01, 0.03, 0.1, 0.3}) {
    o.end_mass_fraction = f;
    const auto sc = solver_->solve(m, Electrodes::short_circuit, o);
    ASSERT_TRUE(sc.converged) << sc.message;
    const auto act = sc.active_frequencies_hz();
    ASSERT_GE(act.size(), 3u) << f;
    std::printf("f = %.2f: active resonances %.1f %.1f %.1f Hz\n", f, act[0], act[1], act[2]);
    for (std::size_t k = 1; k < sc.modes.size() && !prev.empty(); ++k)
      EXPECT_LT(sc.modes[k].frequency_hz, prev[k]) << "f " << f << " mode " << k;
    for (std::size_t k = 0; k < 3 && !prev_active.empty(); ++k)
      EXPECT_LT(act[k], prev_active[k]) << "f " << f << " active " << k;
    prev.clear();
    for (const auto& md : sc.modes) prev.push_back(md.frequency_hz);
    prev_active = act;
  }
}

TEST_F(EndMass, LoadedPortModelMatchesTheLoadedDirectSolve) {
  // The modal port model (Lanczos with B = M + fΔM, residual mode from the
  // loaded static shape) against the direct complex solve with the same mass.
  const double f = 0.05;
  const auto m = apc850();
  ModalOptions o;
  o.n_modes = 20;
  o.end_mass_fraction = f;
  const auto port = solver_->port_model(m, o);
  ASSERT_TRUE(port.converged);
  EXPECT_EQ(port.end_mass_fraction, f);
  // Static capacitances do not depend on the mass.
  ModalOptions o0 = o;
  o0.end_mass_fraction = 0.0;
  const auto port0 = solver_->port_model(m, o0);
  EXPECT_NEAR(port.c_static, port0.c_static, 1e-12 * port0.c_static);
  EXPECT_NEAR(port.c_clamped, port0.c_clamped, 1e-12 * port0.c_clamped);
  const RayleighDamping d{0.0, 1e-7};
  const std::vector<double> freqs = frequency_grid(1000, 120000, 1700);
  DirectHarmonicSolver direct(*tube_);
  const auto yd = direct.admittance(m, freqs, d, {}, f);
  const auto ym = admittance_modal(port, freqs, d);
  ModalResult sc, oc;
  sc = solver_->solve(m, Electrodes::short_circuit, o);
  oc = solver_->solve(m, Electrodes::open_circuit, o);
  std::vector<double> peaks = sc.active_frequencies_hz();
  for (double x : oc.active_frequencies_hz()) peaks.push_back(x);
  double worst = 0, worst_all = 0;
  int n_away = 0;
  for (std::size_t i = 0; i < freqs.size(); ++i) {
    const double e = std::abs(std::abs(1.0 / ym[i]) / std::abs(1.0 / yd[i]) - 1);
    worst_all = std::max(worst_all, e);
    bool near = false;
    for (double p : peaks) near |= std::abs(freqs[i] / p - 1) < 0.02;
    if (near) continue;
    ++n_away;
    worst = std::max(worst, e);
    // Same acceptance as the unloaded tube (tests/model/test_harmonic.cpp): 0.1 % in |Z|.
    EXPECT_LT(e, 1e-3) << freqs[i] << " Hz";
  }
  EXPECT_GT(n_away, 50);
  std::printf(
      "loaded (f = %.2f) modal vs direct |Z|: max rel diff %.2e away from peaks (%d pts), "
      "%.2e overall\n",
      f, worst, n_away, worst_all);
}

TEST_F(EndMass, BadFractionIsRefused) {
  const auto m = apc850();
  for (double bad :
       {-0.01, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    ModalOptions o;
    o.end_mass_fraction = bad;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    EXPECT_THROW(solver_->solve(m, Electrodes::short_circuit, o), std::invalid_argument);
    EXPECT_THROW(tube_->mass(bad), std::invalid_argument);
    DirectHarmonicSolver direct(*tube_);
    const double fq[] = {1e3};
    EXPECT_THROW(direct.admittance(m, fq, {}, {}, bad), std::invalid_argument);
  }
}
