// Issue 10 acceptance, CI size: the simulated bench with a fixture (fixture
// capacitance 50–300 pF, lead resistance 1–20 Ω, R1 off by up to 3 %, channel
// skew up to 200 ns), open/short/load standards measured in the same capture.
//  * the fixture's quantities are MEASURED (fixture C, lead R, R1 error, skew);
//  * compensation + deskew bring what an ideal estimator measures (the bench's
//    exact Z_m) to the true transducer impedance within 0.5 % and 0.5° over
//    1–120 kHz away from the peaks (±1.5 % around each resonance/anti-resonance);
//  * end to end with Prony-SS on the dut shots: within the target at 0.05 %
//    noise; at 0.5 % noise (8 shots) noise-limited next to the 82 kHz resonance;
//  * the Kramers–Kronig/passivity check passes on the result and fails when
//    channel 2 is deskewed with the wrong sign.
// The numbers are printed (docs/dsp-methods.md quotes them).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include "acquisition/impedance_assessment.hpp"
#include "dsp/deskew.hpp"
#include "fixture_study.hpp"
#include "tests/support/sim_truth.hpp"

namespace {
using namespace piezo;
using test::FixtureSetting;
namespace fs = std::filesystem;

constexpr FixtureSetting kSettings[] = {
    {"50pF_1ohm_R1-3pct_skew60ns", 50e-12, 1.0, -0.03, 60e-9},
    {"150pF_10ohm_R1+3pct_skew173ns", 150e-12, 10.0, 0.03, 173e-9},
    {"300pF_20ohm_R1+1.5pct_skew200ns", 300e-12, 20.0, 0.015, 200e-9},
};

fs::path tmp_file(const std::string& name) {
  auto d = fs::temp_directory_path() / ("piezobench-fixture-" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d / name;
}

acq::AssessmentOptions options() {
  acq::AssessmentOptions o;
  o.method = "prony";
  o.fmin_hz = 1e3;
  o.fmax_hz = 120e3;
  o.step_hz = 100.0;
  o.prony.prep.max_samples = 6000;  // the pipeline's choice
  o.uncertainty = acq::UncertaintySource::None;
  o.validity = false;
  o.stabilization = false;
  return o;
}

std::vector<double> grid_of(const dsp::ImpedanceResult& r) {
  return std::vector<double>(r.f_hz.data(), r.f_hz.data() + r.f_hz.size());
}
std::vector<std::complex<double>> z_of(const dsp::ImpedanceResult& r) {
  return std::vector<std::complex<double>>(r.z_ohm.data(), r.z_ohm.data() + r.z_ohm.size());
}

class FixtureAcceptance : public ::testing::TestWithParam<FixtureSetting> {};

TEST_P(FixtureAcceptance, CompensationMeetsTheTargetAndTheFixtureIsMeasured) {
  const FixtureSetting s = GetParam();
  const acq::SimSpec spec = test::fixture_spec(s, 1);
  const auto cap = test::measure_capture(spec, 8, true, tmp_file(std::string(s.name) + ".h5"));
  const auto a = acq::assess_impedance(cap, options());
  ASSERT_TRUE(a.calibration);
  const auto& fx = a.calibration->fixture;
  const auto truth = test::true_tube_impedance(spec);
  const auto peaks = test::true_peaks(truth, 120e3);

  // Measured fixture quantities (what the gap diagnosis reports).
  ASSERT_TRUE(fx.fixture_capacitance_f && fx.lead_resistance_ohm && fx.r1_error && fx.skew_s);
  std::printf(
      "[%s] measured: Cp %.2f pF (true %.0f), Rs %.3f ohm (true %.1f), R1 error %+.3f %% (true "
      "%+.1f), skew %.1f ns (true %.0f)\n",
      s.name, *fx.fixture_capacitance_f * 1e12, s.cp_f * 1e12, *fx.lead_resistance_ohm, s.rs_ohm,
      *fx.r1_error * 100, s.r1_tolerance * 100, *fx.skew_s * 1e9, s.skew_s * 1e9);
  // The skew and the open's R1·Cp lag both delay v2; only the open's magnitude
  // roll-off, (ω·R1·Cp)² — 1.4 % at 120 kHz for 50 pF — tells them apart, so a
  // small Cp trades a few pF against a few ns (measured: 53.4 pF, −5.3 ns at 50 pF).
  EXPECT_NEAR(*fx.fixture_capacitance_f, s.cp_f, std::max(0.03 * s.cp_f, 5e-12));
  EXPECT_NEAR(*fx.skew_s, s.skew_s, 8e-9);
  EXPECT_NEAR(*fx.lead_resistance_ohm / s.rs_ohm, 1.0, 0.02);
  EXPECT_NEAR(*fx.r1_error, s.r1_tolerance, 0.002);

  // Compensation alone: the bench's exact Z_m (an ideal estimator), deskewed and corrected.
  const auto zm = test::exact_measured_impedance(spec, 3140.0);
  const auto comp = a.calibration->compensation();
  std::vector<double> f;
  std::vector<std::complex<double>> raw, fixed;
  for (double x = 1e3; x <= 120e3; x += 100.0) f.push_back(x);
  Eigen::VectorXd fv = Eigen::Map<Eigen::VectorXd>(f.data(), Eigen::Index(f.size()));
  Eigen::VectorXcd zv(fv.size());
  for (Eigen::Index k = 0; k < fv.size(); ++k) zv[k] = zm(fv[k]);
  const Eigen::VectorXcd zd = dsp::deskew_impedance(fv, zv, 3140.0, a.skew_applied_s);
  for (Eigen::Index k = 0; k < fv.size(); ++k) {
    raw.push_back(zv[k]);
    fixed.push_back(comp.correct(fv[k], zd[k]));
  }
  const auto e_raw = test::max_error(f, raw, truth, peaks),
             e_fix = test::max_error(f, fixed, truth, peaks);
  std::printf(
      "[%s] exact Z_m: uncompensated %.2f %% / %.2f deg, compensated %.3f %% (%.1f kHz) / %.3f deg "
      "(%.1f kHz)\n",
      s.name, e_raw.mag_pct, e_raw.phase_deg, e_fix.mag_pct, e_fix.mag_f_hz / 1e3, e_fix.phase_deg,
      e_fix.phase_f_hz / 1e3);
  EXPECT_LT(e_fix.mag_pct, 0.5);
  EXPECT_LT(e_fix.phase_deg, 0.5);
  EXPECT_GT(e_raw.mag_pct, 2.0);  // the fixture matters: the comparison is not trivial

  // End to end (Prony-SS on the dut shots), beside the same estimator on a fixture-free bench.
  const auto e_comp = test::max_error(grid_of(a.result), z_of(a.result), truth, peaks);
  const auto e_unc = test::max_error(grid_of(a.uncompensated), z_of(a.uncompensated), truth, peaks);
  acq::SimSpec ideal = spec;
  ideal.effects = model::EffectSet{};
  const auto cap0 =
      test::measure_capture(ideal, 8, false, tmp_file(std::string(s.name) + "-ideal.h5"));
  const auto a0 = acq::assess_impedance(cap0, options());
  const auto e_ideal = test::max_error(grid_of(a0.result), z_of(a0.result), truth, peaks);
  std::printf(
      "[%s] Prony end to end: uncompensated %.2f %% / %.2f deg, compensated %.2f %% (%.1f kHz) / "
      "%.2f deg; "
      "fixture-free bench %.2f %% / %.2f deg\n",
      s.name, e_unc.mag_pct, e_unc.phase_deg, e_comp.mag_pct, e_comp.mag_f_hz / 1e3,
      e_comp.phase_deg, e_ideal.mag_pct, e_ideal.phase_deg);
  // At 0.5 % noise and 8 shots both are set by noise next to the 82 kHz
  // resonance (|Z| ≈ 25 Ω behind R1 = 3140 Ω: v2 is 1 % of v1 there), where it
  // falls from seed to seed (fixture-free, seeds 1–4: 2.2–3.3 %), so only the
  // fixture-free line is held, at what was measured for this seed (2.23 % /
  // 0.96°): Prony-SS with the pole model from t = 0 at its noise-set order
  // (PronyImpedanceOptions::direct_samples = 0) is at 4.87 % / 3.23°, its
  // truncation bias. The bias itself: EndToEndAtLowNoise below.
  EXPECT_LT(e_ideal.mag_pct, 3.5);
  EXPECT_LT(e_ideal.phase_deg, 2.0);
  EXPECT_LT(e_comp.mag_pct, e_unc.mag_pct);
  ASSERT_TRUE(a.kk);
  EXPECT_TRUE(a.kk->pass) << a.kk->note;
  fs::remove_all(tmp_file("").parent_path());
}

// The target end to end where noise does not hide the estimator's bias: the
// 150 pF setting at 0.05 % noise per channel (8 shots), compensated Prony-SS
// within 0.5 % and 0.5° of the true transducer impedance away from the peaks.
// Measured 0.24 % / 0.15° (seeds 2, 3: 0.38 % / 0.25°, 0.41 % / 0.22°); with the
// pole model from t = 0 (no direct samples) 3.47 % / 2.45°: the tube's modes
// above the band, left out by an order set by the noise, enter V2 next to the
// 82 kHz resonance.
TEST(FixtureAcceptanceLowNoise, EndToEndMeetsTheTarget) {
  const FixtureSetting s = kSettings[1];
  const acq::SimSpec spec = test::fixture_spec(s, 1, 0.0005);
  const auto cap = test::measure_capture(spec, 8, true, tmp_file("low-noise.h5"));
  const auto a = acq::assess_impedance(cap, options());
  const auto truth = test::true_tube_impedance(spec);
  const auto e = test::max_error(grid_of(a.result), z_of(a.result), truth, test::true_peaks(truth, 120e3));
  std::printf("[%s, 0.05 %% noise] Prony end to end, compensated: %.3f %% (%.1f kHz) / %.3f deg (%.1f kHz), order %zu\n",
              s.name, e.mag_pct, e.mag_f_hz / 1e3, e.phase_deg, e.phase_f_hz / 1e3,
              a.result.prony ? a.result.prony->order : std::size_t(0));
  EXPECT_LT(e.mag_pct, 0.5);
  EXPECT_LT(e.phase_deg, 0.5);
  fs::remove_all(tmp_file("").parent_path());
}

INSTANTIATE_TEST_SUITE_P(Settings, FixtureAcceptance, ::testing::ValuesIn(kSettings),
                         [](const auto& i) {
                           std::string n = i.param.name;
                           for (auto& c : n)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return n;
                         });

// A wrong deskew sign on a late channel 2 (a delay of 2τ instead of none) makes
// the capacitive transducer look active: the check fails; the right sign passes.
TEST(FixtureKramersKronig, WrongSkewSignFails) {
  const FixtureSetting s = kSettings[1];
  const acq::SimSpec spec = test::fixture_spec(s, 2);
  const auto cap = test::measure_capture(spec, 4, true, tmp_file("kk.h5"));
  auto o = options();
  const auto good = acq::assess_impedance(cap, o);
  ASSERT_TRUE(good.kk);
  EXPECT_TRUE(good.kk->pass) << good.kk->note;
  // The same dut records deskewed with the wrong sign, compensated with the same standards.
  std::vector<const acq::Shot*> dut;
  for (const auto& sh : cap.shots)
    if (sh.role == acq::Role::Dut) dut.push_back(&sh);
  auto rec = acq::average_shots(cap, dut);
  acq::deskew_record(rec, -good.skew_applied_s);
  dsp::PronyImpedanceOptions po = o.prony;
  po.prony.band_hz = 120e3;
  auto bad = dsp::impedance_prony(rec.view(), dsp::make_grid(1e3, 120e3, 100.0), po);
  good.calibration->compensate(bad);
  const auto kk = dsp::kramers_kronig_check(bad.f_hz, bad.z_ohm, Eigen::VectorXd(), o.kk_options);
  std::printf("KK right sign: %s\nKK wrong sign: %s\n", good.kk->note.c_str(), kk.note.c_str());
  EXPECT_FALSE(kk.pass);
  EXPECT_FALSE(kk.passive);
  fs::remove_all(tmp_file("").parent_path());
}

}  // namespace
