// The gap of ONE shot diagnosed in the output-error model (issue 18;
// update/gap_output_error.hpp): on the simulated bench at 2 % noise, the
// injected effect is named with its value (read from the test's own SimSpec,
// never by the diagnosis), a control gives "none", an alias is never a
// verdict; and `piezobench diagnose` runs on a one-shot capture.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "model/effects.hpp"
#include "tests/support/run_cli.hpp"
#include "tests/support/sim_capture.hpp"
#include "ui/capture_fit.hpp"
#include "update/gap_diagnosis.hpp"
#include "update/gap_output_error.hpp"

using namespace piezo;
namespace fs = std::filesystem;

namespace {
fs::path tmp_dir(const std::string& name) { return test::scratch_dir(name); }

acq::SimSpec spec_with(const char* effect, std::uint64_t seed) {
  acq::SimSpec s;
  s.isotropic = true;
  s.set = "YE11=6.66e10,nu12=0.3333,d31=-210e-12,epsT33_rel=2294";
  s.noise_rel = 0.02;  // a few percent, one shot: most recordings people have
  s.seed = seed;
  if (*effect) model::apply_effect_assignment(s.effects, effect);
  return s;
}

update::GapDiagnosis diagnose_one_shot(const acq::SimSpec& spec, const std::string& name) {
  auto sim = acq::make_sim_bench(spec, 3140.0);
  const auto cap = test::sim_capture(sim, test::seed_lab_plan(1), tmp_dir("gap-oe") / (name + ".h5"));
  ui::CaptureFitRequest req;
  req.options.scan_effects = update::supported_gap_effects();
  const auto f = ui::fit_capture(cap, req);
  EXPECT_TRUE(f.result.ok()) << name << ": " << f.result.message;
  return update::gap_from_output_error(f.result, name);
}
}  // namespace

TEST(GapOutputError, OneShotControlHasNoGap) {
  const auto d = diagnose_one_shot(spec_with("", 31), "control");
  std::printf("control: %s\n", d.verdict.c_str());
  EXPECT_EQ(d.method, "output-error");
  EXPECT_EQ(d.verdict_effect, "none") << d.verdict;
  EXPECT_FALSE(d.gap);
  for (const auto& e : d.effects)
    if (e.name == "r1_tolerance" || e.name == "parallel_capacitance") {
      EXPECT_TRUE(e.alias) << e.name;
    }
}

TEST(GapOutputError, OneShotNamesTheInjectedEffectWithItsValue) {
  struct Case {
    const char* assign;
    const char* name;
    double value;
  };
  for (const Case& c : {Case{"series_resistance=30", "series_resistance", 30.0},
                        Case{"channel_skew=1.5e-7", "channel_skew", 1.5e-7}}) {
    const auto d = diagnose_one_shot(spec_with(c.assign, 32), c.name);
    std::printf("%s: %s\n", c.assign, d.verdict.c_str());
    EXPECT_TRUE(d.gap);
    ASSERT_EQ(d.verdict_effect, c.name) << d.verdict;
    ASSERT_FALSE(d.steps.empty());
    const auto& s = d.steps.front();
    // Within 4 of its own sigma (the bench's Debye/FOH discretisation is not
    // the forward model's closed form: a little model error is allowed for).
    EXPECT_LT(std::abs(s.value - c.value), 4.0 * s.sigma) << c.name << " " << s.value << " +- " << s.sigma;
    EXPECT_GT(s.delta_chi2, 25.0);
  }
}

TEST(GapOutputError, DiagnoseRunsOnAOneShotCapture) {
  auto sim = acq::make_sim_bench(spec_with("series_resistance=30", 33), 3140.0);
  const fs::path file = tmp_dir("gap-oe") / "cli.h5";
  test::sim_capture(sim, test::seed_lab_plan(1), file);
  const auto r = test::run_cli("diagnose " + file.string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["method"], "output-error");
  EXPECT_EQ(j["verdict"]["effect"], "series_resistance") << j["verdict_text"];
  EXPECT_GE(j["effects"].size(), 8u);
}
