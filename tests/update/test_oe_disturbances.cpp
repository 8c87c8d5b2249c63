// Issue 33 item 1: a real bench's slow disturbances as nuisance of the
// output-error fit (update/output_error/baseline.hpp), against independent
// truth. The records come from our time-domain divider simulator
// (model::simulate_divider, not the estimator's per-bin prediction) and the
// disturbances from a generator of this file, not the simulated bench's
// (drivers/sim/disturbances: Voss–McCartney pink noise, its own hum model):
// DC offsets, mains hum with harmonics at a random phase, and 1/f noise shaped
// in frequency. What is checked:
//  * a capture without disturbances keeps the white model, number for number
//    the same as with the nuisance model switched off;
//  * with offsets, hum and 1/f noise the fit is at its noise (no lack of
//    fit), the constants within 4 sigma of the truth, their sigmas within 2x
//    of the same record's without the disturbances (the acceptance study's
//    1.5x is a median statement; one record's 1/f draw can take more);
//  * a record long enough to hold two mains cycles tells 50 from 60 Hz and
//    measures the hum's amplitude within 4 sigma; the diagnosis names it as a
//    disturbance, not as an effect of the catalogue;
//  * issue 33 item 2: eight shots of one tube are consistent; eight with a
//    step of epsT33 and d31 after the fourth are not, the step is found where
//    it is with its size within 3 sigma, and the diagnosis names no effect
//    ("non_stationary"); shots with trigger jitter (sampled from a 4x finer
//    simulation at other phases: not the aligner's interpolation) are
//    measured within 0.1 sample (4 sigma) and aligned.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <random>
#include <vector>

#include "dsp/fft.hpp"
#include "model/material_presets.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/transient.hpp"
#include "model/tube_model.hpp"
#include "tests/support/oe_test_tube.hpp"
#include "update/gap_diagnosis.hpp"
#include "update/gap_output_error.hpp"
#include "update/output_error.hpp"

namespace {
using namespace piezo;

struct Record {
  std::vector<double> v1, v2;
  double fs = 10e6;
  std::size_t pre = 200;
};

double rms(const std::vector<double>& v) {
  double a = 0;
  for (double x : v) a += x * x;
  return std::sqrt(a / double(v.size()));
}

// The seed's lab drive (1 V exp_decay at 3000 1/s) through R1 = 3140 Ω into
// the FE tube, white noise of noise_rel of each channel's rms.
// rise_s > 0: the drive rises as a raised cosine over rise_s (an AWG's
// smoothed onset: a sampled jump has no sub-sample position, a rise has).
Record simulate(model::ModalSolver& solver, const update::MaterialClass& cls, const update::TubeParams& truth,
                double fs, std::size_t n, double noise_rel, std::uint64_t seed, std::size_t pre = 200,
                double rise_s = 0.0) {
  Record r;
  r.fs = fs;
  r.pre = pre;
  r.v1.assign(n, 0.0);
  for (std::size_t i = r.pre; i < n; ++i) {
    const double t = double(i - r.pre) / fs;
    r.v1[i] = std::exp(-3000.0 * t) * (t < rise_s ? 0.5 * (1.0 - std::cos(M_PI * t / rise_s)) : 1.0);
  }
  model::ModalOptions mo;
  mo.n_modes = 40;
  const auto port = solver.port_model(cls.e_form(truth), mo);
  model::DividerCircuit c;
  c.r1_ohm = 3140.0;
  r.v2 = model::simulate_divider(port, {0.0, 6e-8}, c, r.v1, fs);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> nd;
  const double s1 = noise_rel * rms(r.v1), s2 = noise_rel * rms(r.v2);
  for (auto& x : r.v1) x += s1 * nd(rng);
  for (auto& x : r.v2) x += s2 * nd(rng);
  return r;
}

// 1/f noise of rms `level`: white noise shaped by 1/√f in frequency (DC zero).
std::vector<double> pink(std::size_t n, double level, std::mt19937_64& rng) {
  std::normal_distribution<double> nd;
  std::vector<double> w(n);
  for (auto& x : w) x = nd(rng);
  dsp::RealFft fft(n);
  std::vector<std::complex<double>> s(fft.bins());
  fft.forward(w.data(), n, s.data());
  s[0] = 0;
  for (std::size_t k = 1; k < s.size(); ++k) s[k] /= std::sqrt(double(k));
  std::vector<double> out(n);
  fft.inverse(s.data(), out.data(), n);
  const double k = level / rms(out);
  for (auto& x : out) x *= k;
  return out;
}

// Offsets, hum (fundamental with 30 % and 15 % harmonics, random phase per
// channel) and 1/f noise of pink_rel of each channel's rms.
void disturb(Record& r, double offset_v, double hum_v[2], double mains_hz, double pink_rel, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ph(0.0, 2 * M_PI);
  std::vector<double>* ch[2] = {&r.v1, &r.v2};
  for (int c = 0; c < 2; ++c) {
    auto& v = *ch[c];
    const double phi = ph(rng);
    const auto p = pink(v.size(), pink_rel * rms(v), rng);
    const double off = (c == 0 ? 1.0 : -0.6) * offset_v;
    for (std::size_t i = 0; i < v.size(); ++i) {
      const double th = 2 * M_PI * mains_hz * double(i) / r.fs + phi;
      v[i] += off + hum_v[c] * (std::sin(th) + 0.3 * std::sin(2 * th) + 0.15 * std::sin(3 * th)) + p[i];
    }
  }
}

// K shots of one tube (`truths[k]` each), each with its own white noise.
std::vector<Record> shots_of(model::ModalSolver& solver, const update::MaterialClass& cls,
                             const std::vector<update::TubeParams>& truths, double noise_rel, std::uint64_t seed) {
  std::vector<Record> out;
  for (std::size_t k = 0; k < truths.size(); ++k)
    out.push_back(simulate(solver, cls, truths[k], 10e6, 20000, noise_rel, seed + 17 * k));
  return out;
}

update::OeData data_of(const std::vector<Record>& shots) {
  update::OeData d;
  d.sample_rate_hz = shots.front().fs;
  d.circuit.r1_ohm = 3140.0;
  for (const auto& r : shots) d.shots.push_back({r.v1, r.v2, r.pre});
  return d;
}

update::OeData data_of(const Record& r) {
  update::OeData d;
  d.sample_rate_hz = r.fs;
  d.circuit.r1_ohm = 3140.0;
  d.shots.push_back({r.v1, r.v2, r.pre});
  return d;
}

double truth_of(const update::TubeParams& t, int i) {
  switch (i) {
    case 0: return t.y_e11;
    case 1: return t.nu12;
    case 2: return t.d31;
    default: return t.eps_t33 / model::kEps0;
  }
}

class OeDisturbances : public test::OeTestTube {
 protected:
  update::TubeParams truth() const {
    update::TubeParams t = nominal;
    t.y_e11 *= 1.04;
    t.nu12 *= 0.96;
    t.d31 *= 1.03;
    t.eps_t33 *= 0.98;
    return t;
  }
};

TEST_F(OeDisturbances, ACleanRecordKeepsTheWhiteModelNumberForNumber) {
  const Record r = simulate(solver, cls, truth(), 10e6, 20000, 0.02, 11);
  const auto with = update::fit_output_error(solver, cls, nominal, data_of(r));
  update::OeOptions off;
  off.disturbances = false;
  const auto without = update::fit_output_error(solver, cls, nominal, data_of(r), off);
  ASSERT_TRUE(with.ok() && without.ok());
  EXPECT_FALSE(with.baseline.any()) << "baseline log10 p " << with.baseline.log10_p << ", 1/f gain "
                                    << with.baseline.pink_delta_2lnl;
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(with.parameters[i].value, without.parameters[i].value) << with.parameters[i].name;
    EXPECT_EQ(with.parameters[i].sigma, without.parameters[i].sigma) << with.parameters[i].name;
  }
  EXPECT_EQ(with.chi2_per_dof, without.chi2_per_dof);
}

TEST_F(OeDisturbances, OffsetsHumAndOneOverFNoiseAreNuisanceNotLackOfFit) {
  const Record clean = simulate(solver, cls, truth(), 10e6, 20000, 0.02, 12);
  Record dist = clean;
  double hum[2] = {0.008, 0.003};
  disturb(dist, 0.005, hum, 60.0, 0.01, 99);
  const auto c = update::fit_output_error(solver, cls, nominal, data_of(clean));
  const auto d = update::fit_output_error(solver, cls, nominal, data_of(dist));
  ASSERT_TRUE(c.ok() && d.ok()) << d.message;
  update::OeOptions off;
  off.disturbances = false;
  const auto white = update::fit_output_error(solver, cls, nominal, data_of(dist), off);
  // Without the nuisance model the disturbances read as a lack of fit.
  EXPECT_TRUE(white.lack_of_fit) << white.chi2_per_dof;
  EXPECT_TRUE(d.baseline.modelled);
  EXPECT_TRUE(d.baseline.pink);
  EXPECT_FALSE(d.lack_of_fit) << "chi2/dof " << d.chi2_per_dof << " limit " << d.chi2_limit << ", band 1e"
                              << d.band_log10_p;
  for (int i = 0; i < 4; ++i) {
    const auto& p = d.parameters[static_cast<std::size_t>(i)];
    const double t = truth_of(truth(), i);
    EXPECT_EQ(p.status, "ok") << p.name << ": " << p.note;
    EXPECT_LT(std::abs(p.value - t), 4.0 * p.sigma_statistical) << p.name << " " << p.value << " truth " << t;
    EXPECT_LT(p.sigma, 2.0 * c.parameters[static_cast<std::size_t>(i)].sigma) << p.name;
  }
  // The pretrigger's means are each channel's offset (+5 mV and -3 mV; the
  // hum and 1/f noise move a 20 µs mean by up to their amplitude).
  ASSERT_TRUE(d.baseline.channel_offsets);
  EXPECT_NEAR(d.baseline.channel_offset_v[0], 0.005, 0.009);
  EXPECT_NEAR(d.baseline.channel_offset_v[1], -0.003, 0.004);
  // The diagnosis reports the disturbances as findings of their own.
  const auto g = update::gap_from_output_error(d, "test");
  EXPECT_EQ(g.verdict_effect, "none") << g.verdict;
  EXPECT_EQ(g.disturbances.size(), 2u) << g.verdict;
}

// 1 MS/s, 40 ms: two 50 Hz cycles in the record — the hum is a hum, not a
// polynomial, its frequency and amplitude measurable.
TEST_F(OeDisturbances, ALongRecordTellsTheMainsFrequencyAndMeasuresTheHum) {
  Record r = simulate(solver, cls, truth(), 1e6, 40000, 0.02, 13);
  double hum[2] = {0.006, 0.0};
  disturb(r, 0.0, hum, 50.0, 0.0, 7);
  update::OeOptions o;
  o.band_hz = 120e3;
  const auto d = update::fit_output_error(solver, cls, nominal, data_of(r), o);
  ASSERT_TRUE(d.ok()) << d.message;
  EXPECT_FALSE(d.lack_of_fit) << d.chi2_per_dof;
  ASSERT_TRUE(d.baseline.modelled);
  EXPECT_EQ(d.baseline.mains_hz, 50.0);
  EXPECT_TRUE(d.baseline.mains_distinguishable);
  EXPECT_EQ(d.baseline.harmonics, 3);
  EXPECT_TRUE(std::isfinite(d.baseline.hum_v));
  // channel 1's hum (6 mV) minus channel 2's (none)
  EXPECT_LT(std::abs(d.baseline.hum_v - 0.006), 4.0 * d.baseline.hum_sigma_v + 1e-4)
      << d.baseline.hum_v << " +- " << d.baseline.hum_sigma_v;
  EXPECT_LT(d.baseline.hum_sigma_v, 0.002);
}

TEST_F(OeDisturbances, EightShotsOfOneTubeAreConsistent) {
  const auto shots = shots_of(solver, cls, std::vector<update::TubeParams>(8, truth()), 0.02, 40);
  const auto r = update::fit_output_error(solver, cls, nominal, data_of(shots));
  ASSERT_TRUE(r.ok()) << r.message;
  ASSERT_TRUE(r.shot_consistency.tested);
  EXPECT_TRUE(r.shot_consistency.consistent) << r.shot_consistency.summary;
  EXPECT_FALSE(r.shot_consistency.aligned);
  EXPECT_EQ(r.shot_consistency.per_shot_pct.size(), 8u);
}

TEST_F(OeDisturbances, AStepBetweenShotsIsFoundWhereItIsAndNoEffectIsNamed) {
  std::vector<update::TubeParams> truths(8, truth());
  for (std::size_t k = 4; k < 8; ++k) {
    truths[k].eps_t33 *= 1.015;
    truths[k].d31 *= 1.015;
  }
  const auto shots = shots_of(solver, cls, truths, 0.02, 60);
  const auto r = update::fit_output_error(solver, cls, nominal, data_of(shots));
  ASSERT_TRUE(r.ok()) << r.message;
  const auto& sc = r.shot_consistency;
  ASSERT_TRUE(sc.tested);
  EXPECT_FALSE(sc.consistent);
  bool found = false;
  for (const auto& ch : sc.changes)
    if (ch.parameter == "epsT33_rel") {
      found = true;
      EXPECT_EQ(ch.kind, "step") << sc.summary;
      EXPECT_EQ(ch.after_shot, 3) << sc.summary;
      EXPECT_LT(std::abs(ch.size_pct - 100 * std::log(1.015)), 3 * ch.sigma_pct) << sc.summary;
    }
  EXPECT_TRUE(found) << sc.summary;
  const auto g = update::gap_from_output_error(r, "test");
  EXPECT_EQ(g.verdict_effect, "non_stationary") << g.verdict;
  EXPECT_TRUE(g.added.empty());
}

TEST_F(OeDisturbances, TriggerJitterIsMeasuredAndTheShotsAligned) {
  // 40 MS/s, sampled at 10 MS/s from four phases: shot k late by 0.75·k
  // samples; a drive rising over 2 µs (a jump's sub-sample position is not
  // in its samples: the jitter of a step drive is measured to the sample).
  const Record fine = simulate(solver, cls, truth(), 40e6, 80000, 0.0, 1, 800, 2e-6);
  std::vector<Record> shots;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> nd;
  for (int k = 0; k < 4; ++k) {
    Record r;
    r.fs = 10e6;
    r.pre = 199;
    // the drive starts at fine sample 800: shot k's sample i is fine sample
    // 4i − 3k (late by 0.75k); 19 999 samples, the pretrigger 199
    for (std::size_t i = 1; i < 20000; ++i) {
      const long j = 4 * long(i) - 3 * k;
      r.v1.push_back(j >= 0 ? fine.v1[std::size_t(j)] : 0.0);
      r.v2.push_back(j >= 0 ? fine.v2[std::size_t(j)] : 0.0);
    }
    const double s1 = 0.02 * rms(r.v1), s2 = 0.02 * rms(r.v2);
    for (auto& x : r.v1) x += s1 * nd(rng);
    for (auto& x : r.v2) x += s2 * nd(rng);
    shots.push_back(std::move(r));
  }
  const auto r = update::fit_output_error(solver, cls, nominal, data_of(shots));
  ASSERT_TRUE(r.ok()) << r.message;
  const auto& sc = r.shot_consistency;
  ASSERT_EQ(sc.jitter_samples.size(), 4u);
  EXPECT_TRUE(sc.aligned);
  // The onset's timing sigma: noise 0.006 V over a slope of about 0.08 V per
  // sample on the ~20 samples of the rise, two noisy records: ≈ 0.025
  // sample; 0.1 is four of it.
  for (int k = 1; k < 4; ++k) EXPECT_NEAR(std::abs(sc.jitter_samples[std::size_t(k)]), 0.75 * k, 0.1) << k;
  EXPECT_TRUE(sc.consistent) << sc.summary;
  EXPECT_FALSE(r.lack_of_fit) << r.chi2_per_dof;
  for (int i = 0; i < 4; ++i) {
    const auto& p = r.parameters[static_cast<std::size_t>(i)];
    EXPECT_LT(std::abs(p.value - truth_of(truth(), i)), 4.0 * p.sigma_statistical) << p.name;
  }
}

}  // namespace
