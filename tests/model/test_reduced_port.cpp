// The reduced-basis port model (model/reduced_port.hpp) against the exact one
// (ModalSolver::port_model: Lanczos on the factorised system) at materials
// around its centre, on two ceramics: each shown mode's ω and |p|, C0,
// C_static, and the port's Q/V over the band the fits use (what the
// output-error fit sees) — and its own error estimates against those errors:
// an answer it calls acceptable must be within the tolerances it claims, and
// the estimates must not fall below the errors they estimate.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "model/material_presets.hpp"
#include "model/modal.hpp"
#include "model/reduced_port.hpp"
#include "model/work_counters.hpp"

using namespace piezo::model;

namespace {

// The output-error fit's coordinates (update/output_error/forward_model.hpp):
// log YE11, relative nu12, log |d31|, log εT33.
PiezoMaterialE at(const IsotropicPiezoParams& p0, const Eigen::Vector4d& x) {
  IsotropicPiezoParams p = p0;
  p.y_e11 *= std::exp(x[0]);
  p.nu12 *= 1.0 + x[1];
  p.d31 *= std::exp(x[2]);
  p.eps_t33 *= std::exp(x[3]);
  return to_e_form(to_d_form(p));
}

struct Errors {
  double omega = 0, p = 0, c0 = 0, cs = 0, q = 0;  // worst relative, over the modes shown at the port
};

Errors errors(const ModalPortModel& e, const ModalPortModel& r) {
  Errors w;
  EXPECT_EQ(e.modes.size(), r.modes.size());
  if (e.modes.size() != r.modes.size()) return {INFINITY, INFINITY, INFINITY, INFINITY, INFINITY};
  for (std::size_t k = 0; k < e.modes.size(); ++k) {
    const auto &a = e.modes[k], &b = r.modes[k];
    EXPECT_EQ(a.residual, b.residual);
    if (a.residual || a.participation * a.participation <= 1e-4 * a.omega * a.omega * e.c_clamped) continue;
    w.omega = std::max(w.omega, std::abs(b.omega / a.omega - 1));
    w.p = std::max(w.p, std::abs(std::abs(b.participation) / std::abs(a.participation) - 1));
  }
  w.c0 = std::abs(r.c_clamped / e.c_clamped - 1);
  w.cs = std::abs(r.c_static / e.c_static - 1);
  const RayleighDamping d{0.0, 1e-7};
  for (double f = 5e3; f <= 200e3; f += 250) {
    const double om = 2 * M_PI * f;
    const auto qe = e.charge_per_volt(om, d), qr = r.charge_per_volt(om, d);
    w.q = std::max(w.q, std::abs(qr - qe) / std::abs(qe));
  }
  return w;
}

}  // namespace

// The four constants' coordinates and, with `mass`, the end mass too (its
// fraction of the tube's mass, about 1 %, with a fifth plus-point).
void check_around(bool mass, int& accepted, int& refused, int& refused_near_centre) {
  for (const char* preset : {"apc850", "pzt5a"}) {
    const auto& mat = find_preset(preset);
    const IsotropicPiezoParams p0 = isotropic_params(mat.material);
    TubeGeometry g;
    g.density_kg_m3 = mat.density_kg_m3;
    TubeModel tm(g);
    ModalSolver solver(tm);
    ModalOptions mo;
    mo.n_modes = 10;
    const double f0 = mass ? 0.01 : 0.0;
    std::vector<ReducedPort::Point> pts{{at(p0, Eigen::Vector4d::Zero()), f0}};
    for (int c = 0; c < 4; ++c) pts.push_back({at(p0, 3e-3 * Eigen::Vector4d::Unit(c)), f0});
    if (mass) pts.push_back({at(p0, Eigen::Vector4d::Zero()), f0 + 3e-3});
    const long solves_before = modal_solves();
    const auto rp = ReducedPort::build(solver, pts, mo);
    ASSERT_TRUE(rp.has_value());
    EXPECT_EQ(modal_solves() - solves_before, static_cast<long>(pts.size()));  // one modal solve a snapshot
    std::mt19937_64 rng(7);
    std::normal_distribution<double> nd;
    for (double reach : {0.0, 1e-4, 1e-3, 3e-3, 1e-2, 2e-2, 5e-2}) {
      Errors worst;
      ReducedPort::Bound worst_bound;
      for (int trial = 0; trial < 4; ++trial) {
        Eigen::Matrix<double, 5, 1> x;
        for (int i = 0; i < 5; ++i) x[i] = nd(rng);
        if (!mass) x[4] = 0;
        x *= reach / x.cwiseAbs().maxCoeff();
        if (reach == 0) x.setZero();
        const auto m = at(p0, x.head<4>());
        ModalOptions me = mo;
        me.end_mass_fraction = std::max(0.0, f0 + x[4]);
        const ModalPortModel e = solver.port_model(m, me);
        ReducedPort::Bound b;
        const long reduced_before = reduced_port_models();
        const ModalPortModel r = rp->port_model(m, me.end_mass_fraction, &b);
        EXPECT_EQ(reduced_port_models() - reduced_before, 1);
        ASSERT_TRUE(e.converged);
        EXPECT_EQ(r.end_mass_fraction, me.end_mass_fraction);
        const Errors w = errors(e, r);
        worst.omega = std::max(worst.omega, w.omega);
        worst.p = std::max(worst.p, w.p);
        worst.q = std::max(worst.q, w.q);
        worst.cs = std::max(worst.cs, w.cs);
        worst_bound.omega = std::max(worst_bound.omega, b.omega);
        worst_bound.participation = std::max(worst_bound.participation, b.participation);
        // The estimates are above the errors (the frequency's within the
        // Lanczos solve's own 1e-10 or so, which the comparison includes).
        if (r.converged) {
          EXPECT_GE(b.omega + 5e-10, w.omega) << preset << " reach " << reach;
          EXPECT_GE(b.participation, w.p) << preset << " reach " << reach;
        }
        if (r.converged && b.acceptable()) {
          ++accepted;
          // What acceptable() promises: ω within 1e-7, |p| within 1e-6
          // (the participation's estimate is 1e3–1e4 above its error on
          // these tubes, and acceptable() takes it up to 1e-3), and so the
          // port's Q/V within 1e-7; the capacitances are variational.
          EXPECT_LE(w.omega, ReducedPort::kOmegaTolerance) << preset << " reach " << reach;
          EXPECT_LE(w.p, 1e-6) << preset << " reach " << reach;
          EXPECT_LE(w.q, 1e-7) << preset << " reach " << reach;
          EXPECT_LE(w.c0, 1e-12);
          EXPECT_LE(w.cs, 1e-12);
        } else {
          ++refused;
          if (reach <= 1e-3) ++refused_near_centre;
        }
      }
      std::printf("%s%s reach %.0e: |dw|/w %.1e (est. %.1e), |dp|/p %.1e (est. %.1e), |dQ|/Q %.1e, dCs %.1e\n",
                  preset, mass ? " (and the end mass)" : "", reach, worst.omega, worst_bound.omega, worst.p,
                  worst_bound.participation, worst.q, worst.cs);
    }
  }
}

TEST(ReducedPort, MatchesTheExactPortModelWhereItSaysSoAndRefusesWhereNot) {
  int accepted = 0, refused = 0, refused_near_centre = 0;
  check_around(false, accepted, refused, refused_near_centre);
  // Near the centre it is used; far out (a veering of pzt5a's modes within 2 %) it is not.
  EXPECT_EQ(refused_near_centre, 0);
  EXPECT_GT(refused, 8);
  EXPECT_GT(accepted, 16);
}

TEST(ReducedPort, WithTheEndMassAsAFifthCoordinate) {
  int accepted = 0, refused = 0, refused_near_centre = 0;
  check_around(true, accepted, refused, refused_near_centre);
  EXPECT_EQ(refused_near_centre, 0);
  EXPECT_GT(accepted, 16);
}

TEST(ReducedPort, RefusesSnapshotsThatCannotMakeABasis) {
  EXPECT_FALSE(ReducedPort::build(std::span<const PortVectors>{}, PiezoMaterialE{}, ModalOptions{}).has_value());
  // A solver without an upper half to compute on (mirror symmetry off).
  const auto& mat = find_preset("apc850");
  TubeGeometry g;
  g.density_kg_m3 = mat.density_kg_m3;
  TubeModel tm(g);
  ModalSolver solver(tm);
  ModalOptions mo;
  mo.mirror_symmetry = false;
  const PiezoMaterialE m = to_e_form(mat.material);
  EXPECT_FALSE(ReducedPort::build(solver, std::vector<ReducedPort::Point>{{m, 0.0}}, mo).has_value());
  EXPECT_FALSE(ReducedPort::build(solver, std::vector<ReducedPort::Point>{}, ModalOptions{}).has_value());
}
