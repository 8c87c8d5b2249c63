// The seed's Appendix A bar vibrators (model/bar_vibrator.hpp) against
// independent truth: IEEE Std 176's resonator formulas for the free-free bars,
// the fixed-mass bar's own characteristic equation kL·tan kL = m/M and its
// lumped limit, the fixed-free bar as half a free-free bar of twice the length
// (another branch of the code), the free capacitance at low frequency, and our
// axisymmetric FE: a long thin radially poled tube's length mode is a 31-mode
// vibrator.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "model/bar_vibrator.hpp"
#include "model/material_presets.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"

namespace {

using namespace piezo::model;
constexpr double kPi = 3.14159265358979323846;

const PiezoMaterialD& apc850() { return find_preset("apc850").material; }

BarGeometry bar(double mass_kg = 0.0) {
  BarGeometry g;
  g.length_m = 0.02;
  g.width_m = 0.005;
  g.thickness_m = 0.002;
  g.density_kg_m3 = find_preset("apc850").density_kg_m3;
  g.end_mass_kg = mass_kg;
  return g;
}

TEST(BarVibrator, FreeFree31IsIeee176) {
  const auto g = bar();
  const auto& m = apc850();
  const auto r = bar_resonances(m, g, BarMode::m31, BarEnds::free_free, 300e3);
  ASSERT_GE(r.size(), 2u);
  // fr = 1/(2L sqrt(rho sE11)); the odd overtones at 3, 5, ... fr.
  const double fr = 1.0 / (2.0 * g.length_m * std::sqrt(g.density_kg_m3 * m.s_e11));
  EXPECT_NEAR(r[0].resonance_hz / fr - 1.0, 0.0, 1e-10);
  EXPECT_NEAR(r[1].resonance_hz / (3.0 * fr) - 1.0, 0.0, 1e-10);
  // IEEE Std 176: k31²/(1 - k31²) = (π/2)(fa/fr) tan[(π/2)(fa - fr)/fr].
  const double k2 = m.d31 * m.d31 / (m.s_e11 * m.eps_t33);
  const double fa = r[0].antiresonance_hz;
  EXPECT_NEAR(kPi / 2 * fa / fr * std::tan(kPi / 2 * (fa - fr) / fr) / (k2 / (1 - k2)) - 1.0, 0.0, 1e-9);
  EXPECT_GT(fa, fr);
}

TEST(BarVibrator, FreeFree33IsIeee176) {
  const auto g = bar();
  const auto& m = apc850();
  const auto r = bar_resonances(m, g, BarMode::m33, BarEnds::free_free, 200e3);
  ASSERT_GE(r.size(), 1u);
  // fa = 1/(2L sqrt(rho sD33)), sD33 = sE33(1 - k33²).
  const double k2 = m.d33 * m.d33 / (m.s_e33 * m.eps_t33);
  const double fa = 1.0 / (2.0 * g.length_m * std::sqrt(g.density_kg_m3 * m.s_e33 * (1 - k2)));
  EXPECT_NEAR(r[0].antiresonance_hz / fa - 1.0, 0.0, 1e-10);
  // IEEE Std 176: k33² = (π/2)(fr/fa) tan[(π/2)(fa - fr)/fa].
  const double fr = r[0].resonance_hz;
  EXPECT_NEAR(kPi / 2 * fr / fa * std::tan(kPi / 2 * (fa - fr) / fa) / k2 - 1.0, 0.0, 1e-9);
  // The 33 bar couples far more strongly than the 31 bar of the same ceramic.
  const auto r31 = bar_resonances(m, g, BarMode::m31, BarEnds::free_free, 200e3);
  EXPECT_GT(r[0].k_eff, 1.5 * r31[0].k_eff);
}

TEST(BarVibrator, FixedMassMeetsItsCharacteristicEquation) {
  const auto& m = apc850();
  for (double ratio : {0.5, 2.0, 10.0}) {
    const auto g = bar(ratio * bar().mass_kg());
    const auto r = bar_resonances(m, g, BarMode::m31, BarEnds::fixed_mass, 200e3);
    ASSERT_GE(r.size(), 1u) << ratio;
    // Short circuit: kL tan(kL) = m/M, k = ω sqrt(rho sE11).
    const double kl = 2 * kPi * r[0].resonance_hz * std::sqrt(g.density_kg_m3 * m.s_e11) * g.length_m;
    EXPECT_NEAR(kl * std::tan(kl) * ratio - 1.0, 0.0, 1e-9) << ratio;
  }
  // A heavy mass: the lumped spring-mass f = sqrt(K/(M + m/3))/(2π), K = A/(sE11 L),
  // to O((m/M)²).
  const double big = 1000.0 * bar().mass_kg();
  const auto g = bar(big);
  const auto r = bar_resonances(m, g, BarMode::m31, BarEnds::fixed_mass, 20e3);
  ASSERT_GE(r.size(), 1u);
  const double stiffness = g.width_m * g.thickness_m / (m.s_e11 * g.length_m);
  const double lumped = std::sqrt(stiffness / (big + g.mass_kg() / 3)) / (2 * kPi);
  EXPECT_NEAR(r[0].resonance_hz / lumped - 1.0, 0.0, 1e-5);
}

TEST(BarVibrator, FixedFreeIsHalfAFreeFreeBarOfTwiceTheLength) {
  const auto& m = apc850();
  for (BarMode mode : {BarMode::m31, BarMode::m33}) {
    auto half = bar(0.0);
    auto whole = bar();
    whole.length_m = 2 * half.length_m;
    const auto a = bar_resonances(m, half, mode, BarEnds::fixed_mass, 250e3);
    const auto b = bar_resonances(m, whole, mode, BarEnds::free_free, 250e3);
    ASSERT_EQ(a.size(), b.size()) << to_string(mode);
    ASSERT_GE(a.size(), 2u);
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_NEAR(a[i].resonance_hz / b[i].resonance_hz - 1.0, 0.0, 1e-10) << to_string(mode) << " " << i;
      EXPECT_NEAR(a[i].antiresonance_hz / b[i].antiresonance_hz - 1.0, 0.0, 1e-10) << to_string(mode) << " " << i;
    }
  }
}

TEST(BarVibrator, LowFrequencyAdmittanceIsTheFreeCapacitance) {
  const auto& m = apc850();
  for (BarMode mode : {BarMode::m31, BarMode::m33})
    for (BarEnds ends : {BarEnds::free_free, BarEnds::fixed_mass}) {
      const auto g = bar(ends == BarEnds::fixed_mass ? bar().mass_kg() : 0.0);
      const double w = 2 * kPi * 1.0;  // 1 Hz, five decades below the first resonance
      const auto y = bar_admittance(m, g, mode, ends, w);
      EXPECT_NEAR(y.real(), 0.0, 1e-30);
      EXPECT_NEAR(y.imag() / w / bar_constants(m, g, mode).c_free - 1.0, 0.0, 1e-8)
          << to_string(mode) << " " << to_string(ends);
    }
}

TEST(BarVibrator, RefusesWhatItCannotModel) {
  auto g = bar();
  g.length_m = 0;
  EXPECT_THROW(bar_constants(apc850(), g, BarMode::m31), std::invalid_argument);
  EXPECT_THROW(bar_admittance(apc850(), bar(), BarMode::m31, BarEnds::free_free, -1.0), std::invalid_argument);
  auto m = apc850();
  m.d33 = 10.0 * m.d33;  // k33 > 1
  EXPECT_THROW(bar_constants(m, bar(), BarMode::m33), std::invalid_argument);
}

// A long thin radially poled tube: its first length-extensional mode has only
// the axial stress T1 and the radial field E3 = V/t, a 31-mode vibrator along
// the length (the hoop contracts freely far below the ring frequency). What
// the 1-D bar leaves out is the wall's radial inertia (Rayleigh-Love): a hoop
// stress of order (f/f_ring)² of the free contraction, f_ring = c/(2π r). At
// L = 100 mm, f/f_ring ≈ 0.16: measured FE/bar - 1 = -0.10 % short circuit,
// -0.25 % open (the induced field's hoop strain is held back too); at 200 mm
// both shrink about fourfold (-0.018 %, -0.051 %). A thinner wall changes
// neither (t/r 0.105 → 0.041: -0.12 %, -0.28 %), so it is not the wall's
// non-uniform field. Asserted: the 1-D limit is approached as (f/f_ring)²
// and reached within 0.1 % at 200 mm.
struct TubeVsBar {
  double short_rel = 0, open_rel = 0, k_rel = 0;
};

TubeVsBar tube_vs_31_bar(double length_m, int n_axial) {
  const auto& preset = find_preset("apc850");
  TubeGeometry tg;
  tg.inner_diameter_m = 0.009;
  tg.outer_diameter_m = 0.010;
  tg.length_m = length_m;
  tg.density_kg_m3 = preset.density_kg_m3;
  MeshOptions mo;
  mo.n_radial = 1;
  mo.n_axial = n_axial;
  const TubeModel tube(tg, mo);
  ModalSolver solver(tube);
  ModalOptions opt;
  opt.n_modes = 6;
  opt.shift_hz = 100.0;
  const auto e = to_e_form(preset.material);
  auto first_active = [&](Electrodes el) {
    const auto res = solver.solve(e, el, opt);
    EXPECT_TRUE(res.converged);
    for (const auto& md : res.modes)
      if (md.electrically_active && md.symmetry == Symmetry::symmetric) return md.frequency_hz;
    return 0.0;
  };
  const double fs = first_active(Electrodes::short_circuit);
  const double fo = first_active(Electrodes::open_circuit);
  BarGeometry g = bar();
  g.length_m = length_m;
  const auto r = bar_resonances(preset.material, g, BarMode::m31, BarEnds::free_free, 0.3 / length_m * 1e4);
  EXPECT_GE(r.size(), 1u);
  if (r.empty() || !(fs > 0) || !(fo > fs)) return {1, 1, 1};
  const double k_fe = std::sqrt(1.0 - (fs / fo) * (fs / fo));
  std::printf("L %.0f mm: FE %.2f / %.2f Hz, 31 bar %.2f / %.2f Hz\n", 1e3 * length_m, fs, fo, r[0].resonance_hz,
              r[0].antiresonance_hz);
  return {fs / r[0].resonance_hz - 1.0, fo / r[0].antiresonance_hz - 1.0, k_fe / r[0].k_eff - 1.0};
}

TEST(BarVibrator, LongThinTubeLengthModeTendsToThe31Bar) {
  const TubeVsBar a = tube_vs_31_bar(0.100, 40), b = tube_vs_31_bar(0.200, 80);
  // Within 0.1 % at 200 mm (f/f_ring ≈ 0.08), the coupling within 0.5 %.
  EXPECT_LT(std::abs(b.short_rel), 1e-3) << b.short_rel;
  EXPECT_LT(std::abs(b.open_rel), 1e-3) << b.open_rel;
  EXPECT_LT(std::abs(b.k_rel), 5e-3) << b.k_rel;
  // The gap is the radial inertia's: below the bar (a stiffer hoop would be
  // above it), and it falls like (f/f_ring)², fourfold per doubled length
  // (more than threefold asserted).
  EXPECT_LT(a.short_rel, 0.0);
  EXPECT_LT(a.open_rel, 0.0);
  EXPECT_GT(a.short_rel / b.short_rel, 3.0) << a.short_rel << " " << b.short_rel;
  EXPECT_GT(a.open_rel / b.open_rel, 3.0) << a.open_rel << " " << b.open_rel;
}

}  // namespace
