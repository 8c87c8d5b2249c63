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

// Seed Appendix C's other parameterisations and its own protocol (APC850).
namespace {

SensitivityResult run_form(SensitivityForm form, bool seed_protocol) {
  const auto& p = find_preset("apc850");
  TubeGeometry g;
  g.density_kg_m3 = p.density_kg_m3;
  SensitivityOptions o;
  o.form = form;
  o.seed_protocol = seed_protocol;
  return form_sensitivity(g, p.material, o);
}

const SensitivityCase& find_case(const SensitivityResult& r, const std::string& name, double factor) {
  for (const auto& c : r.cases)
    if (c.name == name && c.factor == factor) return c;
  throw std::runtime_error("no case " + name);
}

void expect_same(const SensitivityCase& a, const SensitivityCase& b) {
  ASSERT_TRUE(a.solved && b.solved) << a.name << " / " << b.name;
  ASSERT_EQ(a.short_modes.size(), b.short_modes.size());
  ASSERT_EQ(a.open_modes.size(), b.open_modes.size());
  for (std::size_t k = 0; k < a.short_modes.size(); ++k)
    EXPECT_NEAR(a.short_modes[k].perturbed_hz, b.short_modes[k].perturbed_hz, 1e-7 * b.short_modes[k].perturbed_hz);
  for (std::size_t k = 0; k < a.open_modes.size(); ++k)
    EXPECT_NEAR(a.open_modes[k].perturbed_hz, b.open_modes[k].perturbed_hz, 1e-7 * b.open_modes[k].perturbed_hz);
  EXPECT_NEAR(a.perturbed.c_static_f, b.perturbed.c_static_f, 1e-9 * std::abs(b.perturbed.c_static_f));
}

// "Matters" as above (kMatters), over the physical cases of each constant.
void expect_seed_reading(const SensitivityResult& r, SensitivityForm form) {
  const auto& params = sensitivity_params(form);
  for (std::size_t i = 0; i < params.size(); ++i) {
    double m = 0;
    int valid = 0;
    for (const auto& c : r.cases)
      if (c.index == static_cast<int>(i) && c.valid) {
        m = std::max(m, c.max_abs_change);
        ++valid;
      }
    ASSERT_GT(valid, 0) << params[i].name;
    if (params[i].seed_says_sensitive) {
      EXPECT_GT(m, kMatters) << params[i].name;
    } else {
      EXPECT_LT(m, kMatters) << params[i].name;
    }
  }
}

}  // namespace

TEST(Sensitivity, EngineeringFormCoincidesWithTheDFormWhereTheAlgebraSays) {
  // sE12 = −ν12/YE11 and sE13 = −ν13/YE33 (eq 13), sE44 = 1/G: scaling ν12 or
  // ν13 scales sE12 or sE13 alone, and G × 2 is sE44 × ½ — the same material,
  // so the same FE numbers (to the solver's tolerance).
  const auto d = run_form(SensitivityForm::d, true), eng = run_form(SensitivityForm::engineering, true);
  expect_same(find_case(eng, "nu12", 2.0), find_case(d, "sE12", 2.0));
  expect_same(find_case(eng, "nu13", 2.0), find_case(d, "sE13", 2.0));  // both outside the physical domain
  const auto d_half = run_form(SensitivityForm::d, false);
  expect_same(find_case(eng, "G", 2.0), find_case(d_half, "sE44", 0.5));
}

TEST(Sensitivity, EngineeringAndEFormsReadAsTheSeedSays) {
  // App. C.1 (Table C.2): only YE11 and ν12 of the five engineering constants
  // move the impedance; App. C.2: cE11, cE12, cE13, cE33, e31, e33 and εS33 all
  // do, cE44, e15 and εS11 not. Doubled and halved, physical cases only.
  expect_seed_reading(run_form(SensitivityForm::engineering, false), SensitivityForm::engineering);
  expect_seed_reading(run_form(SensitivityForm::e, false), SensitivityForm::e);
}

TEST(Sensitivity, SeedProtocolSolvesAndFlagsTheNonPhysicalMaterials) {
  const auto r = run_form(SensitivityForm::d, true);
  ASSERT_EQ(r.cases.size(), 10u);  // one factor per constant: elastic x2, piezoelectric and dielectric x0.5
  EXPECT_TRUE(r.converged) << r.message;
  for (const auto& c : r.cases) {
    EXPECT_EQ(c.factor, seed_factor(sensitivity_params(SensitivityForm::d)[static_cast<std::size_t>(c.index)].group));
    EXPECT_TRUE(c.solved) << c.name << ": " << c.reason;
    const bool seed_ran_non_physical = c.name == "sE13" || c.name == "epsT33";
    EXPECT_EQ(c.physical, !seed_ran_non_physical) << c.name;
    EXPECT_EQ(c.valid, c.physical) << c.name;
    if (!c.physical) {
      EXPECT_FALSE(c.reason.empty());
    }
    EXPECT_TRUE(std::isfinite(c.max_abs_change)) << c.name;
  }
  // εT33 halved: the free thin tube's capacitance is εT33·2πR̄L/t to the
  // thin-wall order, so C_static halves (measured −50.20 %; εT33 doubled,
  // a physical case, gives +100.2 %: the same 0.2 % from the wall's thickness).
  EXPECT_NEAR(find_case(r, "epsT33", 0.5).c_static_change, -0.5, 0.01);
  // sE13 doubled, outside the domain, still moves nothing beyond 1 % (the seed's reading of Table C.1).
  EXPECT_LT(find_case(r, "sE13", 2.0).max_abs_change, kMatters);
}
