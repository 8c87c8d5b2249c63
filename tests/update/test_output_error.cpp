// The output-error estimator (update/output_error.hpp) against independent truth:
//  * our own time-domain divider simulator (model::DividerSimulator: first-order
//    hold, a matrix exponential per step — a different path from the estimator's
//    per-DFT-bin prediction) with known constants, with and without noise;
//  * the captures of ../shared/corpus/refsim-v1, written by another tool, with
//    truth.json beside each (PIEZO_OE_CORPUS_CASES: the cases of this program;
//    the `validate` program runs all twenty and checks the aggregate).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <nlohmann/json.hpp>

#include "acquisition/capture_file.hpp"
#include "model/material_presets.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/transient.hpp"
#include "model/tube_model.hpp"
#include "model/work_counters.hpp"
#include "jobs/pipeline/capture_fit.hpp"
#include "tests/support/oe_test_tube.hpp"
#include "update/gap_diagnosis.hpp"
#include "update/gap_output_error.hpp"
#include "update/output_error.hpp"

namespace {
using namespace piezo;

struct Synthetic {
  std::vector<double> v1, v2;
  update::TubeParams truth;
  double beta = 6e-8;
  std::size_t pretrigger = 200;
};

// The seed's lab drive (1 V exp_decay at 3000 1/s, 200 idle samples first),
// 20000 samples at 10 MS/s, through R1 = 3140 Ω into the FE tube.
Synthetic simulate(model::ModalSolver& solver, const update::MaterialClass& cls,
                   const update::TubeParams& truth, double noise_rel, std::uint64_t seed,
                   std::size_t pre = 200, double beta = 6e-8) {
  Synthetic s;
  s.truth = truth;
  s.beta = beta;
  s.pretrigger = pre;
  const double fs = 10e6;
  const std::size_t n = 20000;
  s.v1.assign(n, 0.0);
  for (std::size_t i = pre; i < n; ++i) s.v1[i] = std::exp(-3000.0 * double(i - pre) / fs);
  model::ModalOptions mo;
  mo.n_modes = 40;  // more than the estimator's 16: its truncation is part of what is tested
  const auto port = solver.port_model(cls.e_form(truth), mo);
  model::DividerCircuit c;
  c.r1_ohm = 3140.0;
  s.v2 = model::simulate_divider(port, {0.0, s.beta}, c, s.v1, fs);
  if (noise_rel > 0) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> nd;
    auto rms = [](const std::vector<double>& v) {
      double a = 0;
      for (double x : v) a += x * x;
      return std::sqrt(a / double(v.size()));
    };
    const double s1 = noise_rel * rms(s.v1), s2 = noise_rel * rms(s.v2);
    for (auto& x : s.v1) x += s1 * nd(rng);
    for (auto& x : s.v2) x += s2 * nd(rng);
  }
  return s;
}

update::OeData data_of(const Synthetic& s) {
  update::OeData d;
  d.sample_rate_hz = 10e6;
  d.circuit.r1_ohm = 3140.0;
  d.shots.push_back({s.v1, s.v2, s.pretrigger});
  return d;
}

double truth_of(const update::TubeParams& t, const std::string& name) {
  if (name == "YE11") return t.y_e11;
  if (name == "nu12") return t.nu12;
  if (name == "d31") return t.d31;
  return t.eps_t33 / model::kEps0;
}

class OutputErrorSimulated : public test::OeTestTube {
 protected:
  update::TubeParams truth() const {
    update::TubeParams t = nominal;
    t.y_e11 *= 1.05;
    t.nu12 *= 0.95;
    t.d31 *= 1.04;
    t.eps_t33 *= 0.97;
    return t;
  }
  // One shot of the lab drive through a lead of r_lead ohms the fit does not
  // know, 1 % noise on each channel (a lack of fit: the scan refits). The
  // shot's samples live in the fixture (OeShot holds spans).
  std::vector<double> lead_v1, lead_v2;
  update::OeData with_lead(double r_lead, std::uint64_t seed) {
    const auto s = simulate(solver, cls, truth(), 0.0, 11);  // the clean drive
    model::ModalOptions mo;
    mo.n_modes = 40;
    const auto port = solver.port_model(cls.e_form(truth()), mo);
    model::DividerCircuit c;
    c.r1_ohm = 3140.0;
    c.r_lead_ohm = r_lead;
    std::vector<double> v1 = s.v1, v2 = model::simulate_divider(port, {0.0, s.beta}, c, s.v1, 10e6);
    std::mt19937_64 rng(seed);
    for (auto* v : {&v1, &v2}) {
      double ms = 0;
      for (double x : *v) ms += x * x;
      std::normal_distribution<double> nd(0.0, 0.01 * std::sqrt(ms / double(v->size())));
      for (auto& x : *v) x += nd(rng);
    }
    lead_v1 = std::move(v1);
    lead_v2 = std::move(v2);
    update::OeData d;
    d.sample_rate_hz = 10e6;
    d.circuit.r1_ohm = 3140.0;
    d.shots.push_back({lead_v1, lead_v2, s.pretrigger});
    return d;
  }
};

#ifndef PIEZO_OE_VALIDATE  // the make-test program; the validate one runs the study below
// Noise-free: what is left is the two simulators' difference (first-order
// hold vs band-limited input, ≤ 1e-3 of the response in the band) and the
// estimator's 16-mode truncation against 40 modes: a few 1e-3 at most.
TEST_F(OutputErrorSimulated, NoiseFreeRecoversTheConstants) {
  const auto s = simulate(solver, cls, truth(), 0.0, 1);
  const auto r = update::fit_output_error(solver, cls, nominal, data_of(s));
  ASSERT_TRUE(r.ok()) << r.message;
  for (int i = 0; i < 4; ++i) {
    const auto& p = r.parameters[static_cast<std::size_t>(i)];
    const double t = truth_of(s.truth, p.name);
    EXPECT_NEAR(p.value / t, 1.0, i == 1 || i == 2 ? 5e-3 : 2e-3) << p.name;
  }
  EXPECT_NEAR(r.damping.beta / s.beta, 1.0, 0.02);
}

// One shot at 2 % noise: every constant ok and within 4 statistical sigma of
// the truth (the chance of a 4-sigma excursion is 6e-5 per constant), the
// chi-square test passes (the model is the simulator's), and the sigma are
// those of a real measurement (0.05 … 5 %).
TEST_F(OutputErrorSimulated, OneNoisyShotIsWithinItsSigma) {
  const auto s = simulate(solver, cls, truth(), 0.02, 7);
  const auto r = update::fit_output_error(solver, cls, nominal, data_of(s));
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_FALSE(r.lack_of_fit) << "chi2/dof " << r.chi2_per_dof << " limit " << r.chi2_limit;
  EXPECT_EQ(r.noise_source.rfind("pretrigger", 0), 0u) << r.noise_source;
  for (int i = 0; i < 4; ++i) {
    const auto& p = r.parameters[static_cast<std::size_t>(i)];
    const double t = truth_of(s.truth, p.name);
    EXPECT_EQ(p.status, "ok") << p.name << ": " << p.note;
    EXPECT_LT(std::abs(p.value - t), 4.0 * p.sigma_statistical)
        << p.name << " " << p.value << " truth " << t << " sigma " << p.sigma_statistical;
    EXPECT_GT(p.sigma / std::abs(p.value), 5e-4) << p.name;
    EXPECT_LT(p.sigma / std::abs(p.value), 0.05) << p.name;
  }
  EXPECT_TRUE(std::isfinite(r.corr_nu12_d31));
}

TEST_F(OutputErrorSimulated, BadInputIsRefusedWithAMessage) {
  update::OeData d;
  d.sample_rate_hz = 10e6;
  EXPECT_THROW(update::fit_output_error(solver, cls, nominal, d), std::invalid_argument);
  std::vector<double> z(4000, 0.0), nan(4000, NAN);
  d.shots.push_back({z, z, 0});
  EXPECT_THROW(update::fit_output_error(solver, cls, nominal, d), std::invalid_argument);
  d.shots[0] = {nan, z, 0};
  EXPECT_THROW(update::fit_output_error(solver, cls, nominal, d), std::invalid_argument);
}
// The fit on two threads (update/output_error.hpp, OeOptions::threads: the
// later starts, the effect scan and the exact Jacobians' models side by side)
// gives the same answer, to the last bit, as on one: every task starts from
// the same state and every FE model is a function of its parameters alone.
// A capture with an effect (a 20 Ω lead) so that the scan refits under a lack
// of fit, the path with the most tasks.
TEST_F(OutputErrorSimulated, TwoThreadsGiveTheSameAnswerAsOne) {
  const update::OeData d = with_lead(20.0, 12);
  update::OeOptions o1;
  o1.scan_effects = update::supported_gap_effects();
  o1.threads = 1;
  update::OeOptions o2 = o1;
  o2.threads = 2;
  const auto r1 = update::fit_output_error(solver, cls, nominal, d, o1);
  const auto r2 = update::fit_output_error(solver, cls, nominal, d, o2);
  ASSERT_TRUE(r1.ok()) << r1.message;
  ASSERT_TRUE(r2.ok()) << r2.message;
  EXPECT_EQ(r1.evaluations, r2.evaluations);
  EXPECT_EQ(r1.chi2_per_dof, r2.chi2_per_dof);
  ASSERT_EQ(r1.parameters.size(), r2.parameters.size());
  for (std::size_t i = 0; i < r1.parameters.size(); ++i) {
    EXPECT_EQ(r1.parameters[i].value, r2.parameters[i].value) << r1.parameters[i].name;
    EXPECT_EQ(r1.parameters[i].sigma, r2.parameters[i].sigma) << r1.parameters[i].name;
  }
  ASSERT_EQ(r1.effects.size(), r2.effects.size());
  for (std::size_t i = 0; i < r1.effects.size(); ++i) {
    EXPECT_EQ(r1.effects[i].name, r2.effects[i].name);
    EXPECT_EQ(r1.effects[i].value, r2.effects[i].value) << r1.effects[i].name;
    EXPECT_EQ(r1.effects[i].delta_chi2, r2.effects[i].delta_chi2) << r1.effects[i].name;
    EXPECT_EQ(r1.effects[i].fe_models, r2.effects[i].fe_models) << r1.effects[i].name;
  }
  EXPECT_TRUE(r1.lack_of_fit);  // (the path under test)
  // The held-out predictions (update/gap_output_error.hpp: without and with
  // each candidate, side by side on two threads) — here on the fit's own data.
  update::OeHeldout ho;
  ho.data = d;
  ho.description = "the fit capture";
  const auto d1 = update::gap_from_output_error(r1, "fit", solver, cls, ho, o1);
  const auto d2 = update::gap_from_output_error(r2, "fit", solver, cls, ho, o2);
  EXPECT_EQ(d1.verdict_effect, d2.verdict_effect);
  ASSERT_TRUE(d1.chi2_heldout && d2.chi2_heldout);
  EXPECT_EQ(*d1.chi2_heldout, *d2.chi2_heldout);
  EXPECT_EQ(d1.heldout_shrink.has_value(), d2.heldout_shrink.has_value());
  if (d1.heldout_shrink && d2.heldout_shrink) {
    EXPECT_EQ(*d1.heldout_shrink, *d2.heldout_shrink);
  }
  ASSERT_EQ(d1.effects.size(), d2.effects.size());
  for (std::size_t i = 0; i < d1.effects.size(); ++i) {
    EXPECT_EQ(d1.effects[i].name, d2.effects[i].name);
    EXPECT_EQ(d1.effects[i].heldout_shrink.has_value(), d2.effects[i].heldout_shrink.has_value()) << d1.effects[i].name;
    if (d1.effects[i].heldout_shrink && d2.effects[i].heldout_shrink) {
      EXPECT_EQ(*d1.effects[i].heldout_shrink, *d2.effects[i].heldout_shrink) << d1.effects[i].name;
    }
  }
}

// The effect scan on its surrogate (OeOptions::scan_surrogate: reduced bases
// of the FE port model, each run's answer evaluated again exactly) against
// the scan on exact models only, on a capture with a lack of fit (a 20 Ω
// lead) so that every kind of run happens: the same effects, verdicts and
// flags, the values within a hundredth of their sigmas and the Δχ² within
// the runs' own stopping rule (½χ² falling by less than 1e-2 an
// iteration), the five constants untouched — for fewer modal solves.
TEST_F(OutputErrorSimulated, TheScanOnItsSurrogateAgreesWithTheExactScan) {
  const update::OeData d = with_lead(20.0, 13);
  update::OeOptions exact;
  exact.scan_effects = update::supported_gap_effects();
  exact.scan_surrogate = false;
  update::OeOptions surrogate = exact;
  surrogate.scan_surrogate = true;
  const long m0 = model::modal_solves();
  const auto re = update::fit_output_error(solver, cls, nominal, d, exact);
  const long m1 = model::modal_solves();
  const auto rs = update::fit_output_error(solver, cls, nominal, d, surrogate);
  const long m2 = model::modal_solves();
  ASSERT_TRUE(re.ok()) << re.message;
  ASSERT_TRUE(rs.ok()) << rs.message;
  EXPECT_TRUE(re.lack_of_fit);  // (the path under test)
  std::printf("modal solves: exact scan %ld, on the surrogate %ld\n", m1 - m0, m2 - m1);
  EXPECT_LT(m2 - m1, m1 - m0);
  for (std::size_t i = 0; i < re.parameters.size(); ++i) {
    EXPECT_EQ(re.parameters[i].value, rs.parameters[i].value) << re.parameters[i].name;
    EXPECT_EQ(re.parameters[i].sigma, rs.parameters[i].sigma) << re.parameters[i].name;
  }
  ASSERT_EQ(re.effects.size(), rs.effects.size());
  for (const auto& e : re.effects) {
    const auto it = std::find_if(rs.effects.begin(), rs.effects.end(), [&](const auto& x) { return x.name == e.name; });
    ASSERT_NE(it, rs.effects.end()) << e.name;
    std::printf("%-24s value %.6g / %.6g, sigma %.3g, dchi2 %.6g / %.6g\n", e.name.c_str(), e.value, it->value,
                e.sigma, e.delta_chi2, it->delta_chi2);
    EXPECT_EQ(e.significant, it->significant) << e.name;
    EXPECT_EQ(e.explains, it->explains) << e.name;
    EXPECT_EQ(e.alias, it->alias) << e.name;
    EXPECT_EQ(e.linearised, it->linearised) << e.name;
    EXPECT_EQ(e.law, it->law) << e.name;
    EXPECT_NEAR(e.delta_chi2, it->delta_chi2, 0.02 + 1e-4 * std::abs(e.delta_chi2)) << e.name;
    if (e.sigma > 0) {
      EXPECT_LE(std::abs(e.value - it->value), 0.01 * e.sigma) << e.name;
    }
  }
}
#endif  // PIEZO_OE_VALIDATE

#ifdef PIEZO_OE_VALIDATE
// Issue 17's own study: twenty tubes drawn within ±15 % of the nominal
// constants (and β within 4e-8 … 1.2e-7 s), ONE shot each of the seed's lab
// drive at a noise level drawn in 1 … 5 % per channel, half with 200 idle
// samples before the step, half starting at it. The truth is the simulator's
// (40 modes, first-order hold); the estimator starts from the nominal
// material. Acceptance: in >= 19 of 20 tubes YE11 and εT33 within 1 %, nu12
// and d31 within 3 %; across all, >= 95 % of the ok constants within 3 sigma
// and none beyond 5 sigma.
// Measured (2026-11-25): 14/20 within the bounds — NOT met. The honesty part
// holds (68 ok constants, all within 3 sigma, none beyond 5). Two causes:
// at 3-5 % noise one shot gives nu12 and d31 a sigma of 2-4 % (the misses
// are at 0.5-2.4 sigma), and in 5 of the 10 records with a 200-sample
// pretrigger chi2/dof is 1.3-2.7 on the model's own data: the pretrigger
// means remove the DAQ offsets only to sigma/sqrt(200), a constant that does
// not average down, so the fit is flagged "lack of fit" (not identifiable).
// Projecting the residual's mean out (tried) brings every chi2/dof to ~1 and
// 80/80 ok constants within 3 sigma here, but then corpus case 02 (2.4 % end
// mass, one shot) passes the chi2 test and reports YE11 ok at -8.4 sigma:
// the chi2 test alone cannot see that end mass in one shot.
TEST_F(OutputErrorSimulated, TwentyTubesOneShotOneToFivePercentNoise) {
  std::mt19937_64 rng(20261125);
  std::uniform_real_distribution<double> spread(0.85, 1.15), noise(0.01, 0.05), lbeta(std::log(4e-8), std::log(1.2e-7));
  int within_bounds = 0, ok = 0, within3 = 0, beyond5 = 0;
  double seconds = 0, expected_in = 0;
  std::vector<double> secs;
  for (int k = 0; k < 20; ++k) {
    update::TubeParams t = nominal;
    t.y_e11 *= spread(rng);
    t.nu12 *= spread(rng);
    t.d31 *= spread(rng);
    t.eps_t33 *= spread(rng);
    const double nr = noise(rng), beta = std::exp(lbeta(rng));
    const std::size_t pre = k % 2 ? 0 : 200;
    const auto s = simulate(solver, cls, t, nr, 1000 + static_cast<std::uint64_t>(k), pre, beta);
    const auto r = update::fit_output_error(solver, cls, nominal, data_of(s));
    EXPECT_TRUE(r.ok()) << "tube " << k << ": " << r.message;
    seconds += r.seconds;
    secs.push_back(r.seconds);
    bool in = r.ok();
    // The chance that the bounds hold for an unbiased estimate with the fit's
    // own statistical sigmas (the study has no chain errors): what the data
    // allow, independent of this estimator (correlations ignored).
    double p_in = 1.0;
    for (int i = 0; i < 4 && i < static_cast<int>(r.parameters.size()); ++i) {
      const auto& p = r.parameters[static_cast<std::size_t>(i)];
      const double bound = (i == 0 || i == 3) ? 0.01 : 0.03;
      const double s = std::abs(p.sigma_statistical / truth_of(t, p.name));
      p_in *= s > 0 ? std::erf(bound / (s * std::sqrt(2.0))) : 1.0;
    }
    expected_in += p_in;
    std::printf("tube %2d noise %.1f %% pre %3zu chi2/dof %.2f %3d models %.2f s:", k, 100 * nr, pre,
                r.chi2_per_dof, r.evaluations, r.seconds);
    for (int i = 0; i < 4 && i < static_cast<int>(r.parameters.size()); ++i) {
      const auto& p = r.parameters[static_cast<std::size_t>(i)];
      const double tv = truth_of(t, p.name), rel = p.value / tv - 1.0, z = (p.value - tv) / p.sigma;
      const double bound = (i == 0 || i == 3) ? 0.01 : 0.03;
      in = in && std::abs(rel) <= bound;
      if (p.status == "ok") {
        ++ok;
        within3 += std::abs(z) <= 3.0;
        beyond5 += std::abs(z) > 5.0;
        EXPECT_LE(std::abs(z), 5.0) << "tube " << k << " " << p.name << " ok at " << z << " sigma";
      }
      std::printf(" %s %+.2f%% (%+.1fs %s)", p.name.c_str(), 100 * rel, z, p.status == "ok" ? "ok" : "n.i.");
    }
    std::printf("%s\n", in ? "" : "  OUT OF BOUNDS");
    within_bounds += in;
  }
  std::sort(secs.begin(), secs.end());
  std::printf("within bounds %d/20 (an unbiased estimate with these sigmas: %.1f/20 expected); ok constants %d: "
              "within 3 sigma %d, beyond 5 sigma %d; fit median %.2f s, mean %.2f s\n",
              within_bounds, expected_in, ok, within3, beyond5, 0.5 * (secs[9] + secs[10]), seconds / 20);
  EXPECT_GE(within_bounds, 19);
  EXPECT_EQ(beyond5, 0);
  if (ok > 0) {
    EXPECT_GE(double(within3), 0.95 * double(ok));
  }
}
#endif  // PIEZO_OE_VALIDATE

// ---- the corpus written by another tool ----------------------------------
const std::filesystem::path kCorpus = std::filesystem::path(PIEZO_SOURCE_DIR) / "../shared/corpus/refsim-v1";

struct CaseResult {
  std::string name, effect;
  int ok_constants = 0, within3 = 0, beyond5 = 0;
};

CaseResult check_case(const std::string& name) {
  CaseResult out;
  out.name = name;
  std::ifstream is(kCorpus / name / "truth.json");
  EXPECT_TRUE(is.good()) << "no truth.json for case " << name;
  const auto truth = nlohmann::json::parse(is);
  out.effect = truth["effect"].is_null() ? "none" : truth["effect"]["name"].get<std::string>();
  const auto cap = acq::read_capture(kCorpus / name / "fit.h5");
  jobs::CaptureFitRequest req;
  const auto fit = jobs::fit_capture(cap, req);
  const auto& r = fit.result;
  EXPECT_TRUE(r.ok()) << name << ": " << r.message;  // an estimate from every capture
  const std::pair<const char*, const char*> keys[] = {
      {"YE11", "YE11_pa"}, {"nu12", "nu12"}, {"d31", "d31_c_per_n"}, {"epsT33_rel", "epsT33_rel"}};
  for (std::size_t i = 0; i < 4; ++i) {
    const auto& p = r.parameters[i];
    EXPECT_EQ(p.name, keys[i].first);
    const double t = truth["material"][keys[i].second].get<double>();
    const double rel = (p.value - t) / std::abs(t), z = (p.value - t) / p.sigma;
    std::printf("case %s (%s) %-10s %+7.3f %%  %+6.2f sigma  %s\n", name.c_str(), out.effect.c_str(),
                p.name.c_str(), 100 * rel, z, p.status.c_str());
    if (out.effect == "none") {
      // The bounds for the controls: 1 % YE11 and epsT33, 3 % nu12 and d31.
      const double bound = (i == 1 || i == 2) ? 0.03 : 0.01;
      EXPECT_LT(std::abs(rel), bound) << name << " " << p.name;
      EXPECT_EQ(p.status, "ok") << name << " " << p.name << ": " << p.note;
    }
    if (p.status == "ok") {
      ++out.ok_constants;
      out.within3 += std::abs(z) <= 3.0;
      out.beyond5 += std::abs(z) > 5.0;
      // Never a confident wrong answer.
      EXPECT_LE(std::abs(z), 5.0) << name << " " << p.name << " is ok at " << z << " sigma";
    }
  }
  return out;
}

std::vector<std::string> corpus_cases() {
  std::vector<std::string> v;
  std::stringstream ss(PIEZO_OE_CORPUS_CASES);
  std::string c;
  while (std::getline(ss, c, ',')) v.push_back(c);
  return v;
}

#ifdef PIEZO_OE_VALIDATE

#define PIEZO_OE_CORPUS_TEST AllTwentyCasesGiveAnEstimateAndNoConfidentWrongAnswer
#else
#define PIEZO_OE_CORPUS_TEST ThreeCasesGiveAnEstimateAndNoConfidentWrongAnswer
#endif
TEST(OutputErrorCorpus, PIEZO_OE_CORPUS_TEST) {
  if (!std::filesystem::exists(kCorpus / "01" / "fit.h5")) GTEST_SKIP() << "no corpus at " << kCorpus;
  int ok = 0, within3 = 0, beyond5 = 0;
  for (const auto& c : corpus_cases()) {
    const auto r = check_case(c);
    ok += r.ok_constants;
    within3 += r.within3;
    beyond5 += r.beyond5;
  }
  std::printf("ok constants %d: within 3 sigma %d, beyond 5 sigma %d\n", ok, within3, beyond5);
  EXPECT_EQ(beyond5, 0);
  // The aggregate: >= 95 % of the ok constants within 3 sigma.
  if (ok > 0) {
    EXPECT_GE(double(within3), 0.95 * double(ok));
  }
}

}  // namespace

#ifdef PIEZO_OE_VALIDATE
// Issue 18's foundation: each catalogue effect fitted as a sixth parameter of
// the output-error model on every corpus capture (one shot or four); which one
// lowers χ² most, whether it is significant and explains the capture.
TEST(OutputErrorCorpus, EffectScanOnEveryCase) {
  if (!std::filesystem::exists(kCorpus / "01" / "fit.h5")) GTEST_SKIP() << "no corpus at " << kCorpus;
  int named = 0, injected = 0, controls_none = 0, controls = 0, aliased_named_other = 0, false_names = 0;
  int constants_scored = 0, constants_within = 0;
  std::vector<double> shrinks;  // held-out shrink of the correct verdicts
  for (int k = 1; k <= 20; ++k) {
    char c[8];
    std::snprintf(c, sizeof c, "%02d", k);
    std::ifstream is(kCorpus / c / "truth.json");
    const auto truth = nlohmann::json::parse(is);
    const std::string effect = truth["effect"].is_null() ? "none" : truth["effect"]["name"].get<std::string>();
    const auto cap = acq::read_capture(kCorpus / c / "fit.h5");
    jobs::CaptureFitRequest req;
    req.options.scan_effects = {"series_resistance", "daq_input_resistance", "parallel_capacitance",
                                "dielectric_loss",   "channel_skew",         "channel_gain",
                                "r1_tolerance",      "mass_loading",         "mechanical_damping"};
    const auto cm = jobs::capture_model(cap, req.material, req.isotropic);
    const auto r = jobs::fit_capture(cap, req, cm).result;
    ASSERT_TRUE(r.ok()) << c;
    // The chirp held out (issue 18: the fit's model predicts its v2 from its v1).
    const auto ho_cap = acq::read_capture(kCorpus / c / "holdout.h5");
    update::OeHeldout ho;
    ho.data = jobs::capture_oe_data(ho_cap, std::nullopt);
    ho.description = std::string(c) + "/holdout.h5";
    const auto d = update::gap_from_output_error(r, c, *cm.solver, cm.cls, ho, req.options);
    const std::string top = d.verdict_effect;
    const update::OeEffect* found = nullptr;
    for (const auto& e : r.effects)
      if (e.name == top) found = &e;
    if (found && top == effect) {
      // Its value against the truth, and the constants refitted with it.
      const double tv = truth["effect"]["value"].get<double>();
      std::printf("    %s %.4g +- %.2g (truth %.4g, %+.1f sigma);", top.c_str(), found->value, found->sigma, tv,
                  (found->value - tv) / found->sigma);
      const std::pair<const char*, double> con[] = {
          {"YE11_pa", found->material.y_e11}, {"nu12", found->material.nu12},
          {"d31_c_per_n", found->material.d31}, {"epsT33_rel", found->material.eps_t33 / model::kEps0}};
      // Within the estimation issue's bounds: 3 of the fit's own sigmas
      // (covariance_rel: ln YE11, nu12 relative, ln |d31|, ln εT33).
      for (int i = 0; i < 4; ++i) {
        const double rel = std::log(con[i].second / truth["material"][con[i].first].get<double>());
        const double sig = found->covariance_rel.rows() > i ? std::sqrt(found->covariance_rel(i, i)) : NAN;
        std::printf(" %s %+.2f%% (%+.1f sigma)", con[i].first, 100 * rel, rel / sig);
        ++constants_scored;
        constants_within += std::abs(rel) <= 3 * sig;
      }
      std::printf("\n");
      if (d.heldout_shrink) shrinks.push_back(*d.heldout_shrink);
    }
    std::printf("case %s %-22s shots %d chi2 %.2f band %.1f lof %d -> %-22s |", c, effect.c_str(), r.shots_used,
                r.chi2_per_dof, r.band_log10_p, int(r.lack_of_fit), top.c_str());
    for (const auto& e : r.effects)
      std::printf(" %s %.0f%s%s%s", e.name.substr(0, 8).c_str(), e.delta_chi2, e.alias ? "A" : "",
                  e.significant ? "*" : "", e.explains ? "E" : "");
    std::printf("\n");
    const bool twin = (effect == "channel_gain" && top == "daq_input_resistance") ||
                      (effect == "daq_input_resistance" && top == "channel_gain");
    const bool a_name = top != "none" && top != "unexplained";
    if (effect == "none") {
      ++controls;
      controls_none += top == "none";
      false_names += a_name;
    } else if (effect == "r1_tolerance" || effect == "parallel_capacitance") {
      aliased_named_other += a_name;
    } else {
      ++injected;
      named += top == effect || twin;
      false_names += a_name && !(top == effect || twin);
    }
  }
  std::sort(shrinks.begin(), shrinks.end());
  const double median_shrink = shrinks.empty() ? NAN : shrinks[shrinks.size() / 2];
  std::printf("effects named %d/%d, controls none %d/%d, aliased effects named as another %d, false names %d, "
              "held-out shrink of correct verdicts median %.0f %% (%zu), constants within 3 sigma %d/%d\n",
              named, injected, controls_none, controls, aliased_named_other, false_names, 100 * median_shrink,
              shrinks.size(), constants_within, constants_scored);
  EXPECT_GE(median_shrink, 0.7);
  EXPECT_EQ(constants_within, constants_scored);
  EXPECT_EQ(false_names, 0);  // never a wrong name: "unexplained" instead
  // Issue 18's figures: ≥ 90 % named (gain and DAQ input count as twins),
  // controls none ≥ 90 %, an alias never named as another effect.
  EXPECT_GE(named, (9 * injected + 9) / 10);
  EXPECT_GE(controls_none, (9 * controls + 9) / 10);
  EXPECT_EQ(aliased_named_other, 0);
}
#endif
