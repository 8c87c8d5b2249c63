// The 3-1 SDOF ring of seed §2.3.1 (eqs 25-55, model/analytic_ring.hpp):
// (1) its formulas against independent closed forms — the admittance's pole
// and zero, eq 40 vs eq 41, the equivalent circuit of eqs 45-55, the static
// limit; (2) the FE tube model in the thin-ring limit against eqs 42-44.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "model/analytic_ring.hpp"
#include "model/material_presets.hpp"
#include "model/modal.hpp"

using namespace piezo::model;

namespace {

// The seed's Fig 18 parameters (§3.3.1): a = 8.75 mm, ℓ = 20 mm, εT33 = 1.594e-8 F/m,
// ρ = 7600, d31 = −175 pC/N, sE11 = 15.8e-12 m²/N; wall of the Do 19 / Di 16 mm tube.
PiezoMaterialD fig18_material() {
  // sE11, d31 as in Table 2. The printed εT33 = 1.594e-8 F/m is 1800 ε0, not Table 2's
  // 1594 ε0 (1.411e-8 F/m) — kept as printed; these tests need only some k31 < 1.
  PiezoMaterialD m = find_preset("apc850").material;
  m.eps_t33 = 1.594e-8;
  return m;
}
RingGeometry fig18_geometry() { return {8.75e-3, 1.5e-3, 20e-3, 7600.0}; }

// Relative error allowed between two evaluations of the same rational function
// in different algebraic forms: a few hundred ulps near the pole.
constexpr double kAlgebra = 1e-12;

}  // namespace

TEST(AnalyticRing, SeedFig18Values) {
  const auto r = analytic_ring(fig18_material(), fig18_geometry());
  // Hand-evaluated: k31² = 175²e-24 / (15.8e-12 · 1.594e-8) = 0.121598...
  EXPECT_NEAR(r.k31 * r.k31, 175e-12 * 175e-12 / (15.8e-12 * 1.594e-8), 1e-15);
  // fr = 1/(2π · 8.75e-3 · sqrt(7600 · 15.8e-12)) = 52490.02 Hz (eq 42).
  EXPECT_NEAR(r.omega_r / (2 * M_PI), 52490.02, 0.01);
  // Cf = 2π a ℓ εT33 / t (eq 48); M = 2π a t ℓ ρ (eq 55).
  EXPECT_NEAR(r.c_free / (2 * M_PI * 8.75e-3 * 20e-3 * 1.594e-8 / 1.5e-3), 1.0, kAlgebra);
  EXPECT_NEAR(r.mass_kg / (2 * M_PI * 8.75e-3 * 1.5e-3 * 20e-3 * 7600.0), 1.0, kAlgebra);
}

TEST(AnalyticRing, AntiResonanceRelationAndEq44RoundTrip) {
  for (const auto& p : material_presets()) {
    const auto r = analytic_ring(p.material, fig18_geometry());
    // eq 43 ⇔ eq 44: (ωr/ωa)² = 1 − k31².
    EXPECT_NEAR(std::pow(r.omega_r / r.omega_a, 2), 1.0 - r.k31 * r.k31, kAlgebra) << p.name;
    EXPECT_NEAR(k31_from_frequencies(r.omega_r, r.omega_a), r.k31, kAlgebra) << p.name;
  }
}

TEST(AnalyticRing, AdmittancePoleAndZeroSitAtResonanceAndAntiResonance) {
  const auto r = analytic_ring(fig18_material(), fig18_geometry());
  // Y = jB: B → +∞ just below ωr, → −∞ just above (pole); B changes sign from
  // − to + through ωa (zero), and B(ωa) vanishes to round-off of the terms.
  const double d = 1e-6;
  EXPECT_GT(ring_admittance(r, r.omega_r * (1 - d)).imag(), 1e3 * r.omega_r * r.c_free);
  EXPECT_LT(ring_admittance(r, r.omega_r * (1 + d)).imag(), -1e3 * r.omega_r * r.c_free);
  EXPECT_LT(ring_admittance(r, r.omega_a * (1 - d)).imag(), 0.0);
  EXPECT_GT(ring_admittance(r, r.omega_a * (1 + d)).imag(), 0.0);
  EXPECT_LT(std::abs(ring_admittance(r, r.omega_a)), 1e-9 * r.omega_a * r.c_free);
  // Static limit: Y/(jω) → Cf (eq 48) as ω → 0.
  EXPECT_NEAR(ring_admittance(r, 1e-3).imag() / 1e-3 / r.c_free, 1.0, kAlgebra);
  for (double w : {0.0, 2.0}) EXPECT_EQ(ring_admittance(r, w).real(), 0.0);
}

TEST(AnalyticRing, Eq40AndEquivalentCircuitEqualEq41) {
  const auto m = fig18_material();
  const auto g = fig18_geometry();
  const auto r = analytic_ring(m, g);
  // Eq 51/55 from the mechanical side: C1 = Cm N², L1 = M/N².
  EXPECT_NEAR(r.compliance_m_n * r.turns_ratio * r.turns_ratio / r.c_motional, 1.0, kAlgebra);
  EXPECT_NEAR(r.mass_kg / (r.turns_ratio * r.turns_ratio) / r.l_motional, 1.0, kAlgebra);
  EXPECT_NEAR(r.c_clamped + r.c_motional, r.c_free, kAlgebra * r.c_free);  // eqs 47, 50
  const double a = g.mean_radius_m, l = g.height_m, t = g.wall_m, rho = g.density_kg_m3;
  for (double f : {1e3, 30e3, 52e3, 53e3, 56e3, 57e3, 120e3}) {
    const double w = 2 * M_PI * f, w1 = r.omega_r * r.omega_r;
    const std::complex<double> y41 = ring_admittance(r, w);
    // Eq 40: jω (2π a ℓ / t)[d31²/(a² ρ sE11² (ω1² − ω²)) + εT33 (1 − k31²)].
    const double b40 = w * (2 * M_PI * a * l / t) *
                       (m.d31 * m.d31 / (a * a * rho * m.s_e11 * m.s_e11 * (w1 - w * w)) +
                        m.eps_t33 * (1 - r.k31 * r.k31));
    // Eqs 45-46, 60: jωC0 + 1/(jωL1 + 1/(jωC1)).
    const std::complex<double> j(0, 1);
    const std::complex<double> yc =
        j * w * r.c_clamped + 1.0 / (j * w * r.l_motional + 1.0 / (j * w * r.c_motional));
    EXPECT_NEAR(b40 / y41.imag(), 1.0, kAlgebra) << f;
    EXPECT_NEAR(yc.imag() / y41.imag(), 1.0, 1e-10) << f;  // L1C1 rounds ω1² once more
  }
}

TEST(AnalyticRing, PreconditionsThrowNamingTheFunction) {
  auto expect_throw = [](auto&& f, const std::string& name) {
    try {
      f();
      ADD_FAILURE() << "no throw from " << name;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  auto m = fig18_material();
  auto g = fig18_geometry();
  expect_throw(
      [&] {
        g.wall_m = 0;
        analytic_ring(m, g);
      },
      "RingGeometry::validate");
  g = fig18_geometry();
  expect_throw(
      [&] {
        m.s_e11 = -1;
        analytic_ring(m, g);
      },
      "analytic_ring");
  m = fig18_material();
  expect_throw(
      [&] {
        m.d31 = -1e-9;
        analytic_ring(m, g);
      },
      "analytic_ring");  // k31 > 1
  const auto r = analytic_ring(fig18_material(), g);
  expect_throw([&] { ring_admittance(r, -1.0); }, "ring_admittance");
  expect_throw([&] { k31_from_frequencies(2.0, 1.0); }, "k31_from_frequencies");
}

// ---- FE tube model in the thin-ring limit -------------------------------------------

namespace {

struct FeRing {
  double fr = 0, fa = 0, k31 = 0;  // FE; k31 from the FE pair by eq 44
  AnalyticRing ring;
};

// A short thin tube of the seed's mean radius a = 8.75 mm, wall = height = h, free
// in z (the ring's T_zz = 0). 2 × 2 Q2 elements: the breathing mode is nearly
// uniform over the section; 2 × 4 changes its frequencies by < 1e-7.
FeRing fe_ring(const MaterialPreset& p, double h) {
  const double a = 8.75e-3;
  TubeGeometry g{2 * a - h, 2 * a + h, h, p.density_kg_m3};
  TubeModel tm(g, MeshOptions{2, 2});
  ModalSolver s(tm);
  ModalOptions o;
  o.n_modes = 4;  // rigid z, cross-section rotation (antisymmetric), breathing, …
  const auto e = to_e_form(p.material);
  const auto sc = s.solve(e, Electrodes::short_circuit, o);
  const auto oc = s.solve(e, Electrodes::open_circuit, o);
  EXPECT_TRUE(sc.converged && oc.converged) << sc.message << oc.message;
  FeRing r;
  r.ring = analytic_ring(p.material, ring_geometry(g));
  const auto fsc = sc.active_frequencies_hz(), foc = oc.active_frequencies_hz();
  if (fsc.empty() || foc.empty()) {
    ADD_FAILURE() << p.name << ": no active breathing mode";
    return r;
  }
  r.fr = fsc.front();
  r.fa = foc.front();
  r.k31 = k31_from_frequencies(r.fr, r.fa);
  return r;
}

}  // namespace

TEST(AnalyticRing, FeThinRingMatchesEqs42To44WithinHalfPercent) {
  // Tolerance 0.5 %, of which the chosen ring (t/a = ℓ/a = 0.069) uses at most
  // 0.06 % in fr, 0.04 % in fa and 0.18 % in k31 (all presets). That is the thin-ring
  // approximation's own error, not discretisation: the SDOF model drops T_rr, the
  // 1/r variation of E_r and of the hoop strain across the wall, and the axial
  // Poisson motion of the section — each second order in t/a or ℓ/a (the next test
  // shows the quadratic decay). k31 amplifies the frequency errors:
  // δk/k = (1 − k²)/k² (δfa/fa − δfr/fr) ≈ 6·(−0.03 %). The seed's own tube
  // (t/a = 0.17) would sit at −1.0 % in k31, outside the band — which is why a
  // thinner wall is used here.
  for (const auto& p : material_presets()) {
    const auto r = fe_ring(p, 0.6e-3);
    const double fr = r.ring.omega_r / (2 * M_PI), fa = r.ring.omega_a / (2 * M_PI);
    std::printf(
        "%-7s ring fr %.2f fa %.2f k31 %.5f | FE fr %.2f (%+.4f %%) fa %.2f (%+.4f %%)"
        " k31 %.5f (%+.4f %%)\n",
        p.name.c_str(), fr, fa, r.ring.k31, r.fr, 100 * (r.fr / fr - 1), r.fa,
        100 * (r.fa / fa - 1), r.k31, 100 * (r.k31 / r.ring.k31 - 1));
    EXPECT_NEAR(r.fr / fr, 1.0, 5e-3) << p.name;
    EXPECT_NEAR(r.fa / fa, 1.0, 5e-3) << p.name;
    EXPECT_NEAR(r.k31 / r.ring.k31, 1.0, 5e-3) << p.name;
  }
}

TEST(AnalyticRing, FeDeviationFromTheRingIsSecondOrderInWallAndHeight) {
  // Halving wall and height (0.6 → 0.3 mm) must divide each FE−ring deviation by
  // ~4 (measured 3.96-4.01 for every preset and quantity); the band 3.5-4.5 allows
  // the third-order terms (t/a = 0.069) and shows the FE model tends to eqs 42-44
  // as a limit rather than agreeing by coincidence.
  for (const auto& p : material_presets()) {
    const auto c = fe_ring(p, 0.6e-3), f = fe_ring(p, 0.3e-3);
    const double dev_c[3] = {c.fr / (c.ring.omega_r / (2 * M_PI)) - 1,
                             c.fa / (c.ring.omega_a / (2 * M_PI)) - 1, c.k31 / c.ring.k31 - 1};
    const double dev_f[3] = {f.fr / (f.ring.omega_r / (2 * M_PI)) - 1,
                             f.fa / (f.ring.omega_a / (2 * M_PI)) - 1, f.k31 / f.ring.k31 - 1};
    for (int i = 0; i < 3; ++i) {
      const double ratio = dev_c[i] / dev_f[i];
      std::printf("%-7s %s deviation %+.3e → %+.3e, ratio %.3f\n", p.name.c_str(),
                  i == 0   ? "fr "
                  : i == 1 ? "fa "
                           : "k31",
                  dev_c[i], dev_f[i], ratio);
      EXPECT_GT(ratio, 3.5) << p.name << " " << i;
      EXPECT_LT(ratio, 4.5) << p.name << " " << i;
    }
  }
}

TEST(AnalyticRing, FeStaticCapacitanceTendsToEq48) {
  // The free ring at ω → 0: Cf = 2π a ℓ εT33 / t (eq 48). The FE static capacitance
  // uses the exact 1/r field, 2π ℓ εT33 / ln(ro/ri) = Cf (1 − (t/2a)²/3 + …) plus
  // electromechanical terms of the same order: measured −0.061 … −0.072 % (presets)
  // at t/a = 0.069.
  // Tolerance 0.2 %: both second-order terms with a ~3× margin.
  for (const auto& p : material_presets()) {
    const double a = 8.75e-3, h = 0.6e-3;
    TubeGeometry g{2 * a - h, 2 * a + h, h, p.density_kg_m3};
    TubeModel tm(g, MeshOptions{2, 2});
    ModalSolver s(tm);
    const double c = s.static_capacitance(to_e_form(p.material));
    const auto r = analytic_ring(p.material, ring_geometry(g));
    std::printf("%-7s C_static FE %.6e F, Cf %.6e F (%+.4f %%)\n", p.name.c_str(), c, r.c_free,
                100 * (c / r.c_free - 1));
    EXPECT_NEAR(c / r.c_free, 1.0, 2e-3) << p.name;
  }
}
