// The gap diagnosis on the simulated bench: its data (the shot ensemble)
// against the bench's exact frequency response, and its verdicts against the
// effect the bench injected (read from the test's own SimSpec, never from the
// diagnosis).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "acquisition/divider_record.hpp"
#include "dsp/shot_ensemble.hpp"
#include "model/bench_response.hpp"
#include "model/effects.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"
#include "tests/support/sim_capture.hpp"
#include "tests/support/sim_truth.hpp"
#include "update/gap_diagnosis.hpp"

using namespace piezo;
namespace fs = std::filesystem;

namespace {
fs::path tmp_dir(const std::string& name) { return test::scratch_dir(name); }

acq::SimSpec target_spec() {
  acq::SimSpec s;
  s.isotropic = true;
  s.set = "YE11=6.66e10,nu12=0.3333,d31=-210e-12,epsT33_rel=2294";
  return s;
}
}  // namespace

TEST(ShotEnsemble, EqualsTheBenchsExactResponseAndItsNoiseIsMeasured) {
  for (const char* fx : {"", "channel_skew=1e-7"}) {
    auto spec = target_spec();
    spec.noise_rel = 5e-3;
    spec.seed = 5;
    if (*fx) model::apply_effect_assignment(spec.effects, fx);
    auto sim = acq::make_sim_bench(spec, 3140.0);
    for (const auto& plan : {test::seed_lab_plan(8), test::chirp_plan(8)}) {
      auto cap = test::sim_capture(sim, plan, tmp_dir("ensemble") / "c.h5");
      std::vector<dsp::DividerRecord> recs;
      for (const auto& s : cap.shots) recs.push_back(acq::divider_record(cap, s));
      dsp::ShotEnsembleOptions eo;
      eo.linear_drive = true;  // the simulated AWG interpolates linearly between its samples
      auto e = dsp::impedance_shot_ensemble(recs, eo);
      std::vector<double> f(e.f_hz.data(), e.f_hz.data() + e.f_hz.size());
      auto z = model::bench_impedance(test::sim_port(spec), spec.damping, spec.effects, 3140.0, f);
      double worst = 0, chi2 = 0;
      const std::size_t n = f.size();
      for (std::size_t i = 0; i < f.size(); ++i) {
        const auto l = std::log(e.z_ohm[static_cast<Eigen::Index>(i)] / z[i]);
        worst = std::max(
            worst, std::max(std::fabs(l.real()) / e.sigma_log_mag[static_cast<Eigen::Index>(i)],
                            std::fabs(l.imag()) / e.sigma_phase[static_cast<Eigen::Index>(i)]));
        chi2 += std::pow(l.real() / e.sigma_log_mag[static_cast<Eigen::Index>(i)], 2) +
                std::pow(l.imag() / e.sigma_phase[static_cast<Eigen::Index>(i)], 2);
      }
      std::printf("%s %s: worst |ln ratio|/sigma %.2f, chi2/N %.2f over %zu\n", fx,
                  std::string(to_string(plan.excitation.kind)).c_str(), worst, chi2 / (2.0 * n), n);
      // Unbiased to within its own measured noise: χ²/N near 1, no 5σ point
      // (236 frequencies × 2: a 5σ excursion has probability 3e-4). Since the
      // records' ends are modelled (dsp/record_tail.hpp) the exp_decay σ at
      // low frequencies is 2-3× smaller, and this checks the estimate there
      // that much more closely: before, the end sample's noise hid the
      // truncation of the still-decaying record (−6.8σ in phase at 1 kHz).
      // And with the linear drive's sinc² (ShotEnsembleOptions::linear_drive)
      // the chirp's χ²/N at 90–120 kHz is 1.2 instead of 1.9 (2.3 at 0.05 %
      // noise, where it was 75).
      EXPECT_LT(chi2 / (2.0 * n), 1.3);
      EXPECT_LT(worst, 5.0);
    }
  }
}

// The diagnosis core on exact data (the bench's closed form, model/bench_response,
// 0.3 % σ, no noise added): a lead resistance is named with its value, and an
// effect whose signature another candidate shares is named together with it.
namespace {
// The target tube's FE solver, with the end-mass fraction of the exact data.
struct ExactTube {
  acq::SimSpec spec = target_spec();
  model::ResolvedMaterial mat = model::resolve_material({spec.material, spec.isotropic, spec.set});
  model::TubeModel tube{geometry()};
  model::ModalSolver solver{tube};
  model::TubeGeometry geometry() const {
    model::TubeGeometry g = spec.geometry;
    g.density_kg_m3 = mat.density_kg_m3;
    return g;
  }
  model::ModalPortModel port(double end_mass_fraction) {
    model::ModalOptions mo;
    mo.n_modes = spec.modes;
    mo.end_mass_fraction = end_mass_fraction;
    return solver.port_model(model::to_e_form(mat.d), mo);
  }
};

update::GapData exact_gap_data(const model::ModalPortModel& port, const model::EffectSet& fx,
                               const std::string& what) {
  update::GapData d;
  for (double f = 1e3; f <= 120e3; f *= 1.02) d.f_hz.push_back(f);
  d.z_ohm = model::bench_impedance(port, {0.0, 1e-7}, fx, 3140.0, d.f_hz);
  d.sigma_log_mag.assign(d.size(), 3e-3);
  d.sigma_phase.assign(d.size(), 3e-3);
  d.description = what;
  return d;
}

// The diagnosis from a start near the true constants (the update's answer is never exact).
update::GapDiagnosis diagnose_exact(ExactTube& t, const update::GapData& fit, const update::GapData& ho) {
  auto start = model::isotropic_params(t.mat.d);
  start.nu12 *= 1.003;
  start.d31 *= 0.998;
  update::GapOptions o;
  o.damping_ref_hz = 50e3;
  return update::diagnose_gap(t.solver, update::MaterialClass::isotropic(), start, {0.0, 1e-7}, 3140.0, fit, &ho,
                              o);
}

update::GapDiagnosis diagnose_exact(const model::EffectSet& fx) {
  ExactTube t;
  const auto port = t.port(0.0);
  return diagnose_exact(t, exact_gap_data(port, fx, "exact fit data"), exact_gap_data(port, fx, "exact held-out data"));
}
}  // namespace

TEST(GapDiagnosisExact, LeadResistanceIsNamedWithItsValue) {
  model::EffectSet fx;
  fx.series_resistance_ohm = 10.0;
  const auto d = diagnose_exact(fx);
  EXPECT_EQ(d.verdict_effect, "series_resistance") << d.verdict;
  ASSERT_FALSE(d.steps.empty());
  EXPECT_NEAR(d.steps.front().value, 10.0, 0.2);
  EXPECT_TRUE(d.verdict_alternatives.empty()) << d.verdict;
}

TEST(GapDiagnosisExact, ChannelGainIsNamedOrCalledIndistinguishable) {
  model::EffectSet fx;
  fx.channel_gain = 0.015;
  const auto d = diagnose_exact(fx);
  const bool named = d.verdict_effect == "channel_gain";
  const bool twin = std::find(d.verdict_alternatives.begin(), d.verdict_alternatives.end(),
                              "channel_gain") != d.verdict_alternatives.end();
  std::printf("channel_gain 0.015 on exact data -> %s\n", d.verdict.c_str());
  EXPECT_TRUE(named || twin) << d.verdict;
  // Whatever is named, the report says which candidates it cannot be told from,
  // symmetrically: if A lists B, B lists A.
  for (const auto& a : d.effects)
    for (const auto& n : a.indistinguishable_from)
      for (const auto& b : d.effects)
        if (b.name == n) {
          EXPECT_NE(
              std::find(b.indistinguishable_from.begin(), b.indistinguishable_from.end(), a.name),
              b.indistinguishable_from.end())
              << a.name << " / " << b.name;
        }
}

// End-face mass loading is a linearised direction of the gap model's port
// (GapModel: the end-mass fraction beside the four material coordinates): on
// exact data of a tube with 3 % of its mass on the ends, from a start near the
// true constants, the diagnosis names it. Its value: the fit stops at 0.0273,
// an optimum where the elastic constants take the rest (the held-out gap is
// gone there too); with 4 re-linearisations (the former default) it stopped at
// 0.018, with a one-sided mass slope at 0.0276 after 20. The line held: 10 %.
TEST(GapDiagnosisExact, EndMassIsNamedWithItsValue) {
  ExactTube t;
  const auto d = exact_gap_data(t.port(0.03), {}, "exact, 3 % end mass");
  const auto r = diagnose_exact(t, d, d);
  std::printf("3 %% end mass on exact data -> %s\n", r.verdict.c_str());
  EXPECT_EQ(r.verdict_effect, "mass_loading") << r.verdict;
  ASSERT_FALSE(r.steps.empty());
  EXPECT_NEAR(r.steps.front().value, 0.03, 0.003);
}

// The alias sentence's advice comes from the effect table (issue 41: "calibrate
// the fixture" was advised for any alias, also after the fixture was
// calibrated and for effects no standard measures): every effect of the
// catalogue says what measures it; effects with the same advice are named
// together; an effect that is not in the list is not named.
TEST(EffectTable, EveryEffectSaysWhatSeparatesItFromTheConstants) {
  for (const auto& e : piezo::model::effect_catalogue()) EXPECT_FALSE(e.separated_by.empty()) << e.name;
  const std::string a = piezo::model::separation_advice({"mechanical_damping"});
  EXPECT_EQ(a.find("fixture"), std::string::npos) << a;
  EXPECT_NE(a.find("mechanical_damping with"), std::string::npos) << a;
  const std::string b = piezo::model::separation_advice({"r1_tolerance", "series_resistance", "channel_gain"});
  EXPECT_NE(b.find("series_resistance with the short standard"), std::string::npos) << b;
  EXPECT_NE(b.find("channel_gain with the load standard"), std::string::npos) << b;
  EXPECT_NE(b.find("r1_tolerance with the load standard"), std::string::npos) << b;
  EXPECT_EQ(b.find("mass_loading"), std::string::npos) << b;
  EXPECT_EQ(piezo::model::separation_advice({}), "");
}
