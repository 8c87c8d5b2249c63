// Issue 21: the gap diagnosis on causes that are NOT in its catalogue
// (tests/support/out_of_catalogue.hpp: a parasitic R-L-C branch across the
// terminals, a transversely isotropic truth under the isotropic fit class, a
// wall 3 % off its drawing, an acoustic load on the outer surface), on the
// 36-transducer study's transducers (±12 % of APC850, 1-3 % noise here), the
// seed's exp_decay drive fitted and a chirp held out, one shot or four. The
// cause is known to the TEST only; the diagnosis sees the two captures.
//
// Scored: `unexplained` with one of the top two regions holding the cause's
// band, or `none` where the constants absorb the cause (an alias, documented):
//   wall thickness  the clamped capacitance goes as εS33/ln(Do/Di) and the
//                   wall's stiffness and mass scale together, so εT33 takes
//                   the capacitance's change ln(Do/Di)/ln(Do'/Di) − 1 (checked
//                   here to 1 %) and YE11 the mean radius's: no gap is left in
//                   either capture (both within their χ² limits);
//   material class  the 4mm-class truth's extra constants, where neither
//                   capture shows a gap;
// never a catalogue effect that shrinks the held-out gap by more than half (a
// false name that seems to carry over); controls (no cause) `none`. A
// material-class error changes every mode and the clamped capacitance: its
// "band" is the whole measured one. OOC_CASES (environment) sets the number of
// cases per shot count (default 20: four of each kind and four controls);
// OOC_VERBOSE prints every candidate; the CI subset runs two cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>

#include "model/material_spec.hpp"
#include "tests/support/out_of_catalogue.hpp"
#include "tests/support/sim_capture.hpp"
#include "jobs/pipeline/pipeline.hpp"

using namespace piezo;
namespace fs = std::filesystem;

namespace {

struct OocRun {
  std::string kind;  // "control" or the out-of-catalogue kind
  std::string description;
  double band_lo_hz = 0, band_hi_hz = 0;
  double truth[4] = {0, 0, 0, 0};  // YE11, nu12, d31, epsT33_rel of the true material (its isotropic view)
  double eps_alias = 0;  // wall thickness: the relative εT33 that takes the clamped capacitance's change
  jobs::PipelineResult result;
};

OocRun run_ooc(int kind_index, std::uint64_t seed, double noise, int shots, const fs::path& dir) {
  acq::SimSpec base = test::study_transducer(seed);
  base.noise_rel = noise;
  OocRun out;
  jobs::PipelineRequest req;
  req.instrument = "sim";
  req.plan = test::seed_lab_plan(shots);
  req.plan.setup.transducer_id = "out-of-catalogue";
  req.heldout_plan = test::chirp_plan(shots);
  req.capture_out = (dir / "fit.h5").string();
  if (kind_index < 4) {
    const auto c = test::out_of_catalogue_case(static_cast<test::OocKind>(kind_index), seed, base);
    req.sim = c.spec;
    out.kind = test::to_string(c.kind);
    out.description = c.description;
    out.band_lo_hz = c.band_lo_hz;
    out.band_hi_hz = c.band_hi_hz;
    if (c.kind == test::OocKind::transversely_isotropic) out.band_lo_hz = 0, out.band_hi_hz = 1e12;
    if (c.kind == test::OocKind::wall_thickness) {
      const auto g = c.spec.geometry, t = acq::true_geometry(c.spec);  // declared, true
      out.eps_alias = std::log(g.outer_diameter_m / g.inner_diameter_m) /
                          std::log(t.outer_diameter_m / t.inner_diameter_m) - 1.0;
    }
  } else {
    req.sim = base;
    out.kind = "control";
    out.description = "no cause";
  }
  const auto mat = model::resolve_material({req.sim.material, req.sim.isotropic, req.sim.set});
  const auto iso = model::isotropic_params(mat.d);
  out.truth[0] = iso.y_e11;
  out.truth[1] = iso.nu12;
  out.truth[2] = iso.d31;
  out.truth[3] = iso.eps_t33 / model::kEps0;
  std::atomic<bool> cancel{false};
  out.result = jobs::run_pipeline(req, {}, cancel);
  return out;
}

// A region holds the cause when their bands overlap.
bool region_holds(const update::GapRegion& g, double lo, double hi) { return g.f_lo_hz <= hi && g.f_hi_hz >= lo; }

// The top two regions: the located ones (update/residual_regions.hpp, with
// their phrase; both diagnoses list them first, most significant first),
// else the impedance-domain diagnosis's named regions by their excess χ².
std::vector<const update::GapRegion*> top_regions(const update::GapDiagnosis& d) {
  std::vector<const update::GapRegion*> r;
  for (const auto& g : d.regions)
    if (!g.description.empty()) r.push_back(&g);
  if (r.empty()) {
    for (const auto& g : d.regions)
      if (g.points > 0) r.push_back(&g);
    std::stable_sort(r.begin(), r.end(), [](auto* a, auto* b) { return a->chi2 - 2.0 * a->points > b->chi2 - 2.0 * b->points; });
  }
  if (r.size() > 2) r.resize(2);
  return r;
}

struct OocTally {
  std::map<std::string, std::map<std::string, int>> confusion;  // kind → verdict
  int causes = 0, unexplained_located = 0, absorbed = 0, false_carried = 0, false_names = 0;
  int controls = 0, controls_none = 0, no_diagnosis = 0;
};

void score(const OocRun& r, OocTally& t) {
  if (!r.result.diagnosis) {
    ++t.no_diagnosis;
    t.confusion[r.kind]["(failed)"]++;
    if (r.kind == "control") ++t.controls; else ++t.causes;
    std::printf("  %-24s no diagnosis: %s\n", r.kind.c_str(),
                r.result.warnings.empty() ? "?" : r.result.warnings.back().c_str());
    return;
  }
  const auto& d = *r.result.diagnosis;
  const std::string& v = d.verdict_effect;
  t.confusion[r.kind][v]++;
  const auto top = top_regions(d);
  bool located = false;
  for (const auto* g : top) located = located || region_holds(*g, r.band_lo_hz, r.band_hi_hz);
  if (r.kind == "control") {
    ++t.controls;
    if (v == "none") ++t.controls_none;
  } else {
    ++t.causes;
    if (v == "unexplained" && located) ++t.unexplained_located;
    // Absorbed: no gap in either capture, and (the wall) εT33 moved by the capacitance's change.
    const bool no_gap = !d.gap;
    if (v == "none" && no_gap && r.kind == "transversely_isotropic") ++t.absorbed;
    if (v == "none" && no_gap && r.kind == "wall_thickness" &&
        std::abs(d.material_base.eps_t33 / model::kEps0 / r.truth[3] - 1.0 - r.eps_alias) < 0.01)
      ++t.absorbed;
    if (v != "none" && v != "unexplained") {
      ++t.false_names;
      if (d.heldout_shrink && *d.heldout_shrink > 0.5) ++t.false_carried;
    }
  }
  std::string where;
  for (const auto* g : top) {
    char b[160];
    std::snprintf(b, sizeof b, " [%.1f-%.1f kHz %s]", g->f_lo_hz / 1e3, g->f_hi_hz / 1e3,
                  g->description.empty() ? g->kind.c_str() : g->description.c_str());
    where += b;
  }
  std::printf("  %-24s -> %-20s gap %.2f / held-out %.2f  cause %.1f-%.1f kHz%s%s\n    %s\n", r.kind.c_str(),
              v.c_str(), d.gap_fit, d.gap_heldout.value_or(0), r.band_lo_hz / 1e3, r.band_hi_hz / 1e3,
              located ? " (located)" : "", where.c_str(), r.description.c_str());
  // What the constants took of it (the truth is the test's; the isotropic view of a 4mm-class truth).
  const auto& m = d.material_base;
  std::printf("    constants - truth: YE11 %+.2f %%, nu12 %+.2f %%, d31 %+.2f %%, epsT33 %+.2f %%\n",
              100 * (m.y_e11 / r.truth[0] - 1), 100 * (m.nu12 / r.truth[1] - 1), 100 * (m.d31 / r.truth[2] - 1),
              100 * (m.eps_t33 / model::kEps0 / r.truth[3] - 1));
  if (r.kind == "wall_thickness") std::printf("    (the wall's clamped capacitance: epsT33 %+.2f %%)\n", 100 * r.eps_alias);
  if (std::getenv("OOC_VERBOSE")) {
    for (const auto& e : d.effects)
      std::printf("      %-22s %s value %11.4g +- %9.3g  dchi2 %8.1f  held-out shrink %5.2f%s\n", e.name.c_str(),
                  e.alias ? "alias" : "     ", e.value, e.sigma, e.delta_chi2, e.heldout_shrink.value_or(-9),
                  e.significant ? " *" : "");
    std::printf("      verdict: %s\n", d.verdict.c_str());
  }
}

void print(const OocTally& t) {
  std::printf("\nconfusion (cause -> verdict):\n");
  for (const auto& [k, row] : t.confusion) {
    std::printf("  %-24s", k.c_str());
    for (const auto& [v, n] : row) std::printf(" %s:%d", v.c_str(), n);
    std::printf("\n");
  }
  std::printf("out of catalogue: unexplained and located (top-2 region) %d/%d, absorbed by the constants (none, no "
              "gap; documented aliases) %d, catalogue effects named %d (%d with held-out shrink > 50 %%), controls "
              "none %d/%d, no diagnosis %d\n",
              t.unexplained_located, t.causes, t.absorbed, t.false_names, t.false_carried, t.controls_none,
              t.controls, t.no_diagnosis);
}

fs::path tmp_dir(const std::string& name) { return test::scratch_dir(name); }

}  // namespace

#ifndef PIEZO_OOC_FULL_STUDY
// CI subset: a parasitic branch on one shot (the output-error path), and a
// control on four shots (the impedance-domain path).
TEST(GapOutOfCatalogueCi, ParasiticBranchIsUnexplainedAndLocated) {
  OocTally t;
  const auto r = run_ooc(0, 5, 0.02, 1, tmp_dir("ooc-ci-branch"));
  score(r, t);
  ASSERT_TRUE(r.result.diagnosis);
  const auto& d = *r.result.diagnosis;
  EXPECT_EQ(d.verdict_effect, "unexplained") << d.verdict;
  bool located = false, resonance = false;
  for (const auto* g : top_regions(d)) {
    located = located || region_holds(*g, r.band_lo_hz, r.band_hi_hz);
    if (g->resonance && g->resonance->f_hz >= r.band_lo_hz && g->resonance->f_hz <= r.band_hi_hz) resonance = true;
  }
  EXPECT_TRUE(located) << d.verdict;
  EXPECT_TRUE(resonance) << "the extra resonance detector should find the branch: " << d.verdict;
  print(t);
}

TEST(GapOutOfCatalogueCi, ControlOnFourShotsIsNone) {
  OocTally t;
  const auto r = run_ooc(4, 6, 0.02, 4, tmp_dir("ooc-ci-control"));  // (its own folder: ctest -j runs the two side by side)
  score(r, t);
  ASSERT_TRUE(r.result.diagnosis);
  EXPECT_EQ(r.result.diagnosis->verdict_effect, "none") << r.result.diagnosis->verdict;
}

#else
void ooc_study(int shots) {
  const char* env = std::getenv("OOC_CASES");
  const int n = env ? std::atoi(env) : 20;
  std::mt19937_64 rng(2121);
  std::uniform_real_distribution<double> u(0, 1);
  OocTally t;
  for (int i = 0; i < n; ++i) {
    const int kind = i % 5;  // the four kinds, then a control
    const double noise = 0.01 + 0.02 * u(rng);
    const std::uint64_t seed = 300 + static_cast<std::uint64_t>(i);
    std::printf("case %d (noise %.3f, %d shot%s):\n", i, noise, shots, shots == 1 ? "" : "s");
    score(run_ooc(kind, seed, noise, shots, tmp_dir("ooc-" + std::to_string(shots))), t);
  }
  print(t);
  EXPECT_GE(t.unexplained_located + t.absorbed, 0.9 * t.causes);
  EXPECT_EQ(t.false_carried, 0);
  EXPECT_GE(t.controls_none, 0.9 * t.controls);
}

TEST(GapOutOfCatalogueValidation, OneShot) { ooc_study(1); }
TEST(GapOutOfCatalogueValidation, FourShots) { ooc_study(4); }
#endif
