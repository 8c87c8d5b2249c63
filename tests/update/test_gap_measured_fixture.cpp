// Issue 10's last acceptance item, through the whole pipeline: with
// open/short/load shots in the capture, the fixture capacitance and the R1
// error are MEASURED (held in the gap model at their values, reported under
// "measured") instead of reported as aliases, and the updated εT33 is freed of
// the bias they put on it. The same transducer and fixture without
// calibration shots is the control: there both are aliases and εT33 is off.
// The truth is the test's own SimSpec (the pipeline never sees it).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "acquisition/calibration_plan.hpp"
#include "model/material_presets.hpp"
#include "tests/support/sim_capture.hpp"
#include "jobs/pipeline/pipeline.hpp"
#include "jobs/export/report_export.hpp"

using namespace piezo;
namespace fs = std::filesystem;

namespace {
constexpr double kCp = 150e-12, kR1Err = 0.02, kRs = 5.0, kSkew = 100e-9;

jobs::PipelineResult run(bool calibrate, const fs::path& dir) {
  jobs::PipelineRequest req;
  req.instrument = "sim";
  req.plan = test::seed_lab_plan(16);
  req.sim.isotropic = true;
  req.sim.noise_rel = 0.01;
  req.sim.seed = 5;
  req.sim.effects.parallel_capacitance_f = kCp;
  req.sim.effects.r1_tolerance = kR1Err;
  req.sim.effects.series_resistance_ohm = kRs;
  req.sim.effects.channel_skew_s = kSkew;
  req.capture_out = (dir / (calibrate ? "cal.h5" : "nocal.h5")).string();
  req.heldout_plan = test::chirp_plan(16);
  if (calibrate) req.calibration = acq::parse_calibration_list("open,short,load", 1000.0);
  std::atomic<bool> cancel{false};
  return jobs::run_pipeline(req, {}, cancel);
}

double error_pct(const jobs::PipelineResult& r, const std::string& name) {
  for (const auto& p : r.params)
    if (p.name == name && p.truth) return 100.0 * (p.updated / *p.truth - 1.0);
  ADD_FAILURE() << "no " << name << " row with a truth";
  return 0;
}
double eps_error_pct(const jobs::PipelineResult& r) { return error_pct(r, "epsT33_rel"); }
double worst_elastic_pct(const jobs::PipelineResult& r) {
  double w = 0;
  for (const char* n : {"YE11", "nu12", "d31"}) w = std::max(w, std::abs(error_pct(r, n)));
  return w;
}

const update::EffectReport* find(const update::GapDiagnosis& d, const std::string& n) {
  for (const auto& e : d.effects)
    if (e.name == n) return &e;
  return nullptr;
}
}  // namespace

TEST(GapMeasuredFixture, CalibrationShotsTurnAliasesIntoMeasuredQuantities) {
  const fs::path dir =
      fs::temp_directory_path() / ("piezobench-gapfix-" + std::to_string(::getpid()));
  fs::create_directories(dir);

  const auto plain = run(false, dir);
  ASSERT_TRUE(plain.diagnosis) << (plain.warnings.empty() ? "" : plain.warnings.back());
  ASSERT_FALSE(plain.fixture);
  const auto* cp0 = find(*plain.diagnosis, "parallel_capacitance");
  const auto* r10 = find(*plain.diagnosis, "r1_tolerance");
  ASSERT_TRUE(cp0 && r10);
  EXPECT_TRUE(cp0->alias);
  EXPECT_TRUE(r10->alias);
  const double bias0 = eps_error_pct(plain);

  const auto cal = run(true, dir);
  ASSERT_TRUE(cal.fixture) << (cal.warnings.empty() ? "" : cal.warnings.back());
  ASSERT_TRUE(cal.diagnosis);
  const auto& d = *cal.diagnosis;
  EXPECT_EQ(find(d, "parallel_capacitance"), nullptr) << "a measured effect is not a candidate";
  EXPECT_EQ(find(d, "r1_tolerance"), nullptr);
  EXPECT_EQ(find(d, "series_resistance"), nullptr);
  EXPECT_EQ(find(d, "channel_skew"), nullptr);
  double cp = 0, r1 = 0, rs = 0, skew = 0;
  for (const auto& m : d.measured) {
    if (m.name == "parallel_capacitance") cp = m.value;
    if (m.name == "r1_tolerance") r1 = m.value;
    if (m.name == "series_resistance") rs = m.value;
    if (m.name == "channel_skew") skew = m.value;
  }
  EXPECT_NEAR(cp, kCp, 5e-12);
  EXPECT_NEAR(r1, kR1Err, 0.002);
  EXPECT_NEAR(rs, kRs, 0.2);
  EXPECT_NEAR(skew, kSkew, 2e-9);
  const double bias1 = eps_error_pct(cal);
  const double el0 = worst_elastic_pct(plain), el1 = worst_elastic_pct(cal);
  std::printf("worst of YE11, nu12, d31: without calibration %.3f %%, with %.3f %%\n", el0, el1);
  // With the fixture in the port fit's circuit the elastic constants are back
  // near the noise (their CRB at this noise and shot count is 0.2-0.6 %).
  // Without calibration the lead R and skew bias them too, but by how much
  // depends on the draw AND on the last bits of libm: this machine gives
  // 1.18 %, the same binary with glibc's FMA/AVX2 code paths switched off
  // (GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA, as on a CPU or VM without
  // them) gives 0.80 % on the same capture. It is printed, not asserted (issue 16).
  EXPECT_LT(el1, 0.6);
  std::printf(
      "epsT33 error: without calibration %+.3f %%, with %+.3f %%; measured Cp %.1f pF, R1 error "
      "%+.3f %%; "
      "verdict with calibration: %s\n",
      bias0, bias1, cp * 1e12, 100 * r1, d.verdict_effect.c_str());
  // The circuit alone predicts the alias: at low frequency the divider reads
  // (C_T + Cp)(1 + e) for a true R1 of R1_nom (1 + e), i.e. εT33 high by
  // (1 + Cp/C_T)(1 + e) - 1 ≈ 3.0 % (C_T = 2π ε L / ln(Do/Di) ≈ 14.9 nF,
  // Cp = 150 pF, e = +2 %); a deterministic offset 30 times the noise's
  // (measured: +3.80 %, the same under both libm code paths).
  EXPECT_GT(bias0, 2.0);
  EXPECT_LT(std::abs(bias1), 0.3);
  EXPECT_EQ(d.verdict_effect, "none") << d.verdict;
  // The JSON carries them under "measured", in issue 7's shape.
  const auto j = jobs::diagnosis_json(d);
  ASSERT_EQ(j["measured"].size(), d.measured.size());
  EXPECT_TRUE(j["verdict"].is_object());
  EXPECT_EQ(j["verdict"]["effect"], d.verdict_effect);
  fs::remove_all(dir);
}
