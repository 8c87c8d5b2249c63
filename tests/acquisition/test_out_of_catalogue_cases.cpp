// The out-of-catalogue cases of tests/support/out_of_catalogue.hpp (issue 21):
// each adds exactly its one cause to the study's transducer, inside the
// brief's ranges, where it says it shows, reproducibly from the seed — and
// the simulated bench takes each of them (with the capture's /truth naming it).
#include <gtest/gtest.h>

#include <cstdio>
#include <map>

#include "tests/support/out_of_catalogue.hpp"

using namespace piezo;
using test::OocKind;

namespace {
std::map<std::string, double> truth_map(const acq::SimSpec& s) {
  auto bench = acq::make_sim_bench(s, 3140.0);
  std::map<std::string, double> m;
  for (const auto& [k, v] : bench->physics().truth()) m[k] = v;
  return m;
}
bool same_effects(const model::EffectSet& a, const model::EffectSet& b) {
  for (const auto& info : model::effect_catalogue())
    if (!(a.*(info.field) == b.*(info.field))) return false;
  return true;
}
}  // namespace

TEST(OutOfCatalogueCases, EachAddsOneCauseInRangeAndWhereItShows) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const acq::SimSpec base = test::study_transducer(seed);
    ASSERT_TRUE(base.isotropic);
    const auto bare = test::detail::port_modes(base);
    for (OocKind kind : {OocKind::parasitic_branch, OocKind::transversely_isotropic,
                         OocKind::wall_thickness, OocKind::acoustic_load}) {
      const auto c = test::out_of_catalogue_case(kind, seed, base);
      std::printf("  seed %llu %-22s [%7.0f, %7.0f] Hz  %s\n",
                  static_cast<unsigned long long>(seed), test::to_string(kind), c.band_lo_hz,
                  c.band_hi_hz, c.description.c_str());
      // The catalogue is untouched: the diagnosis has nothing of it to fit.
      EXPECT_TRUE(same_effects(c.spec.effects, base.effects));
      EXPECT_EQ(c.spec.set, base.set);
      EXPECT_EQ(c.spec.damping.beta, base.damping.beta);
      EXPECT_GT(c.band_hi_hz, c.band_lo_hz);
      EXPECT_GE(c.band_lo_hz, 100.0);
      EXPECT_LE(c.band_hi_hz, 1.03 * 120e3);
      const auto& un = c.spec.unmodelled;
      const int causes = static_cast<int>(un.parasitic_branches.size()) +
                         (un.acoustic_impedance_pa_s_m != 0) + (un.wall_thickness_rel != 0) +
                         (c.spec.isotropic != base.isotropic);
      EXPECT_EQ(causes, 1);
      switch (kind) {
        case OocKind::parasitic_branch: {
          ASSERT_EQ(un.parasitic_branches.size(), 1u);
          const auto& r = un.parasitic_branches[0];
          EXPECT_GE(r.k_eff, 0.05);
          EXPECT_LE(r.k_eff, 0.12);
          EXPECT_GE(r.q, 40.0);
          EXPECT_LE(r.q, 200.0);
          EXPECT_GE(r.f_hz, 10e3);
          EXPECT_LE(r.f_hz, 108e3);
          for (const auto& m : bare)  // away from every mode that shows in Z
            if (m.coupling > 1e-4) {
              EXPECT_GE(std::abs(r.f_hz - m.f_hz), 5e3) << m.f_hz;
            }
          EXPECT_LT(c.band_lo_hz, r.f_hz);
          EXPECT_GT(c.band_hi_hz, r.f_hz);
          break;
        }
        case OocKind::transversely_isotropic:
          EXPECT_FALSE(c.spec.isotropic);
          break;
        case OocKind::wall_thickness:
          EXPECT_EQ(std::abs(un.wall_thickness_rel), 0.03);
          break;
        case OocKind::acoustic_load:
          EXPECT_GE(un.acoustic_impedance_pa_s_m, 0.03 * 1.48e6);
          EXPECT_LE(un.acoustic_impedance_pa_s_m, 0.15 * 1.48e6);
          break;
      }
      // Reproducible from the seed.
      const auto again = test::out_of_catalogue_case(kind, seed, base);
      EXPECT_EQ(again.description, c.description);
    }
  }
}

TEST(OutOfCatalogueCases, WallErrorTakesBothSigns) {
  const acq::SimSpec base = test::study_transducer(1);
  int thinner = 0, thicker = 0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    const double rel = test::out_of_catalogue_case(OocKind::wall_thickness, seed, base)
                           .spec.unmodelled.wall_thickness_rel;
    (rel < 0 ? thinner : thicker)++;
  }
  std::printf("  12 seeds: %d thinner, %d thicker\n", thinner, thicker);
  EXPECT_GT(thinner, 0);
  EXPECT_GT(thicker, 0);
}

TEST(OutOfCatalogueCases, TheSimulatedBenchTakesEachAndRecordsIt) {
  const acq::SimSpec base = test::study_transducer(5);
  const std::map<OocKind, std::string> key = {
      {OocKind::parasitic_branch, "unmodelled_parasitic_f_hz"},
      {OocKind::wall_thickness, "unmodelled_wall_thickness_rel"},
      {OocKind::acoustic_load, "unmodelled_acoustic_impedance"}};
  for (const auto& [kind, name] : key) {
    const auto c = test::out_of_catalogue_case(kind, 5, base);
    EXPECT_EQ(truth_map(c.spec).count(name), 1u) << name;
  }
  // The transversely isotropic truth: its sE13 is the preset's, not the isotropic class's sE12.
  const auto ti = test::out_of_catalogue_case(OocKind::transversely_isotropic, 5, base);
  const auto t_iso = truth_map(base), t_ti = truth_map(ti.spec);
  EXPECT_EQ(t_ti.at("sE11"), t_iso.at("sE11"));  // the four overrides are the same
  const auto full = model::resolve_material({ti.spec.material, false, ti.spec.set}).d;
  const auto iso = model::resolve_material({base.material, true, base.set}).d;
  EXPECT_EQ(iso.s_e13, iso.s_e12);  // the isotropic class (§6.4.3)
  EXPECT_NE(full.s_e13, full.s_e12);
  std::printf("  sE13/sE12: truth %.4f, isotropic class %.4f; d33/d31: truth %.3f\n",
              full.s_e13 / full.s_e12, iso.s_e13 / iso.s_e12, full.d33 / full.d31);
}
