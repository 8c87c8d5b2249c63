// Seed Appendix C.1 (model/sensitivity.hpp): each d-form constant doubled and
// halved on the seed's tube (Do 19 / Di 16 / L 20 mm, default 2 × 24 mesh), for
// every preset. The claim under test (eq 16): only sE11, sE12, d31 and εT33 move
// the impedance. Printed tables: ctest -R sensitivity -V.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "model/material_presets.hpp"
#include "model/sensitivity.hpp"

using namespace piezo::model;

namespace {

// "Matters" = some active frequency in the band (short or open circuit) or
// C_static moves by more than 1 % when the constant is doubled or halved.
// Measured (all presets): the six constants the seed calls insensitive move
// nothing by more than 0.15 % (the largest: C_static under d33 halved, +0.149 %
// for APC850) apart from the one weak pzt8 mode below; the four sensitive ones
// move something by at least 8.6 % (pzt8, d31 halved: its second anti-resonance).
// 1 % sits a factor ≥ 6 from both.
constexpr double kMatters = 1e-2;

// pzt8's fourth short-circuit mode (94.5 kHz): a symmetric mode veering with the
// strong 93.6 kHz one, coupling 1.7e-3 (just above the 1e-3 activity threshold)
// and its open-circuit partner 5 Hz above it (coupling 7e-6), so it barely shows
// in |Z|. It involves shear: sE44 doubled moves it −4.0 %, halved +2.4 % — the one
// place the seed's claim fails with this measure (APC850's analogue, 83.9 kHz,
// has coupling 2e-4 and is not active). d15 halved moves it −0.80 %, εT11 doubled
// −0.49 %, still under the threshold.
bool is_pzt8_weak_mode(const std::string& preset, std::size_t k) {
  return preset == "pzt8" && k == 3;
}

SensitivityResult run(const MaterialPreset& p) {
  TubeGeometry g;
  g.density_kg_m3 = p.density_kg_m3;
  return d_form_sensitivity(g, p.material);
}

// Largest |change| of a case, optionally leaving out pzt8's weak mode.
double max_change(const SensitivityCase& c, const std::string& preset, bool skip_weak) {
  double m = std::abs(c.c_static_change);
  for (std::size_t k = 0; k < c.short_modes.size(); ++k)
    if (!(skip_weak && is_pzt8_weak_mode(preset, k)))
      m = std::max(m, std::abs(c.short_modes[k].change));
  for (const auto& t : c.open_modes) m = std::max(m, std::abs(t.change));
  return m;
}

void print(const std::string& name, const SensitivityResult& r) {
  std::printf("%s: nominal short", name.c_str());
  for (double f : r.nominal.short_hz) std::printf(" %.1f", f);
  std::printf(" | open");
  for (double f : r.nominal.open_hz) std::printf(" %.1f", f);
  std::printf(" Hz | C_static %.5e F\n", r.nominal.c_static_f);
  for (const auto& c : r.cases) {
    std::printf("  %-7s x%-4g", d_param_name(c.param), c.factor);
    if (!c.valid) {
      std::printf(" not physical (%s)\n", c.reason.c_str());
      continue;
    }
    for (const auto& t : c.short_modes) std::printf(" %+8.3f", 100 * t.change);
    std::printf(" |");
    for (const auto& t : c.open_modes) std::printf(" %+8.3f", 100 * t.change);
    std::printf(" | C %+8.3f | max %.3f %% MAC ≥ %.3f\n", 100 * c.c_static_change,
                100 * c.max_abs_change, c.min_mac);
  }
}

}  // namespace

TEST(Sensitivity, AppendixCClaimHoldsForEveryPresetExceptPzt8WeakMode) {
  for (const auto& p : material_presets()) {
    const auto r = run(p);
    print(p.name, r);
    ASSERT_TRUE(r.converged) << p.name << ": " << r.message;
    ASSERT_GE(r.nominal.short_hz.size(), 3u) << p.name;
    ASSERT_GE(r.nominal.open_hz.size(), 3u) << p.name;
    for (int i = 0; i < kNumDParams; ++i) {
      const auto d = static_cast<DParam>(i);
      // Doubling or halving one constant can leave the physical domain (sE11 halved:
      // sE not positive definite; d31 doubled: coupling > 1) — one of the two must
      // stay inside for the verdict to rest on something.
      ASSERT_GE(r.valid_cases(d), 1) << p.name << " " << d_param_name(d);
      double worst = 0, worst_without_weak = 0;
      for (const auto& c : r.cases) {
        if (c.param != d || !c.valid) continue;
        worst = std::max(worst, max_change(c, p.name, false));
        worst_without_weak = std::max(worst_without_weak, max_change(c, p.name, true));
      }
      EXPECT_DOUBLE_EQ(worst, r.max_change(d));
      if (seed_says_sensitive(d)) {
        EXPECT_GT(worst, kMatters) << p.name << " " << d_param_name(d);
      } else if (p.name == "pzt8" && d == DParam::s_e44) {
        // Documented exception (see is_pzt8_weak_mode): fails only through that mode.
        EXPECT_GT(worst, kMatters) << "pzt8 sE44 no longer moves the weak mode: update the note";
        EXPECT_LT(worst_without_weak, kMatters);
      } else {
        EXPECT_LT(worst, kMatters) << p.name << " " << d_param_name(d);
      }
    }
  }
}

TEST(Sensitivity, D31ActsThroughTheAntiResonances) {
  // Seed C.1: "d31 influences the anti-resonance frequencies" and εT33 the low-
  // frequency impedance. With short-circuit frequencies and C_static alone d31
  // would look insensitive (thin-wall theory: E3 = 0 in short circuit, T = 0 in the
  // free static tube), so the open-circuit frequencies are part of the measure.
  // Bounds: measured SC ≤ 0.73 %, C_static ≤ 0.023 %, OC ≥ 8.6 % (all presets; pzt8's
  // weak fourth SC mode, which borrows its charge from the strong third, moves −4.7 %
  // and is left out here).
  for (const auto& p : material_presets()) {
    const auto r = run(p);
    for (const auto& c : r.cases) {
      if (c.param != DParam::d31 || !c.valid) continue;
      double sc = 0, oc = 0;
      for (std::size_t k = 0; k < c.short_modes.size(); ++k)
        if (!is_pzt8_weak_mode(p.name, k)) sc = std::max(sc, std::abs(c.short_modes[k].change));
      for (const auto& t : c.open_modes) oc = std::max(oc, std::abs(t.change));
      EXPECT_LT(sc, kMatters) << p.name;
      EXPECT_LT(std::abs(c.c_static_change), 1e-3) << p.name;
      EXPECT_GT(oc, kMatters) << p.name;
    }
    for (const auto& c : r.cases) {  // εT33 scales C_static nearly proportionally
      if (c.param == DParam::eps_t33 && c.valid) {
        EXPECT_NEAR(1 + c.c_static_change, c.factor, 0.01 * c.factor) << p.name;
      }
    }
  }
}

TEST(Sensitivity, PairingByShapeAndPreconditions) {
  const auto& p = find_preset("apc850");
  const auto r = run(p);
  for (const auto& c : r.cases) {
    if (!c.valid) {
      EXPECT_FALSE(c.reason.empty());
      continue;
    }
    ASSERT_EQ(c.short_modes.size(), r.nominal.short_hz.size());
    ASSERT_EQ(c.open_modes.size(), r.nominal.open_hz.size());
    // Small changes leave the shapes alone (MAC > 0.99); the large ones (sE11, sE12)
    // still find a clear partner (measured ≥ 0.73).
    EXPECT_GT(c.min_mac, seed_says_sensitive(c.param) ? 0.5 : 0.99) << d_param_name(c.param);
  }
  SensitivityOptions bad;
  bad.factors = {1.0};
  try {
    d_form_sensitivity(TubeGeometry{}, p.material, bad);
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("SensitivityOptions::validate"), std::string::npos);
  }
  PiezoMaterialD broken = p.material;
  broken.s_e11 = -1;
  try {
    d_form_sensitivity(TubeGeometry{}, broken);
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("d_form_sensitivity"), std::string::npos);
  }
}
