// Seed chapter 5.1.2 on the analytic BVD divider: 10 MS/s, Rayleigh β = 1e-7,
// v1 = 500·e^{−0.001 t} for 5 ms through R1 = 3140 Ω, white noise on v1 and v2
// with std(noise) = level·std(clean channel over the 5 ms record) (the seed's
// definition, 10 % = S/N 20 dB). Prony-SS with 1000 and 3000 samples beside the
// direct FFT (one 5e4 record) and the cross spectra (20 records of 5e4).
//
// Targets (acceptance): features within 0.2 %, |Z| within 1 dB over 1–120 kHz
// away from the peaks (±1.5 % around each true feature). They are asserted where
// the information in the data allows them; where it does not, the test asserts
// that fact through the Cramér–Rao bound instead of loosening a tolerance:
// with 10 % noise the 51/54 kHz circuit poles carry a CRB of ≈0.47 % (1σ) at
// 3000 samples and ≈13 % at 1000, so no unbiased estimator meets 0.2 % there.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "bvd_model.hpp"
#include "crb.hpp"
#include "dsp/features.hpp"
#include "impedance_study.hpp"

namespace {
using namespace piezo;
using cd = std::complex<double>;

const bvd::Bvd& model() {
  static const bvd::Bvd m = bvd::tube_bvd_rayleigh(1e-7);
  return m;
}

study::StudyInput chapter5_input(double level, std::uint64_t seed, std::size_t records) {
  const auto resp = bvd::divider_response(model(), 3140.0, 500.0, 1e-3);
  const double fs = 1e7;
  const std::size_t n = 50000;
  const auto v1c = bvd::sample(resp.v1, fs, n), v2c = bvd::sample(resp.v2, fs, n);
  study::StudyInput in;
  in.sample_rate_hz = fs;
  in.r1_ohm = 3140.0;
  for (std::size_t r = 0; r < records; ++r) {
    in.v1.push_back(bvd::add_noise(v1c, level, seed * 1000 + 2 * r));
    in.v2.push_back(bvd::add_noise(v2c, level, seed * 1000 + 2 * r + 1));
  }
  in.z_true = [](double f) { return model().impedance_at(f); };
  const auto truth = dsp::find_features(in.z_true, 1e3, 120e3, 10.0);
  for (const auto& f : truth.resonances) in.true_resonances_hz.push_back(f.f_hz);
  for (const auto& f : truth.antiresonances) in.true_antiresonances_hz.push_back(f.f_hz);
  return in;
}

// Relative CRB (1σ) of each oscillating circuit pole frequency, ascending.
std::vector<double> pole_crb_rel(double level, std::size_t n) {
  const auto resp = bvd::divider_response(model(), 3140.0, 500.0, 1e-3);
  const auto v1c = bvd::sample(resp.v1, 1e7, 50000), v2c = bvd::sample(resp.v2, 1e7, 50000);
  std::vector<cd> poles;
  crb::Channel c1{{}, level * bvd::std_dev(v1c)}, c2{{}, level * bvd::std_dev(v2c)};
  for (std::size_t i = 0; i < resp.v2.lambda.size(); ++i) {
    const cd l = resp.v2.lambda[i];
    if (l.imag() < 0) continue;
    poles.push_back(l);
    c2.residue.push_back(resp.v2.residue[i]);
    c1.residue.push_back(l == resp.v1.lambda[0] ? resp.v1.residue[0] : cd(0));
  }
  std::vector<std::pair<double, double>> out;
  for (std::size_t i = 0; i < poles.size(); ++i)
    if (poles[i].imag() > 0) {
      const double f = poles[i].imag() / (2 * std::numbers::pi);
      out.push_back({f, crb::pole_frequency_crb_hz(poles, {c1, c2}, 1e7, n, i) / f});
    }
  std::sort(out.begin(), out.end());
  std::vector<double> rel;
  for (auto& p : out) rel.push_back(p.second);
  return rel;
}

void expect_mode(const study::StudyRow& r, std::size_t mode, double tol) {
  ASSERT_LT(mode, r.res_err_rel.size());
  EXPECT_LT(std::abs(r.res_err_rel[mode]), tol) << r.method << " " << r.samples << " resonance " << mode;
  EXPECT_LT(std::abs(r.anti_err_rel[mode]), tol) << r.method << " " << r.samples << " anti-resonance " << mode;
}

TEST(Chapter5Study, TruthHasThreeModes) {
  const auto in = chapter5_input(0.1, 1, 1);
  ASSERT_EQ(in.true_resonances_hz.size(), 3u);
  ASSERT_EQ(in.true_antiresonances_hz.size(), 3u);
}

// The comparison of the seed's §5.1.2 at 10 % noise.
TEST(Chapter5Study, TenPercentNoiseComparison) {
  const auto in = chapter5_input(0.10, 1, 20);
  const std::vector<study::StudyRow> rows{
      study::study_prony(in, 1000),          study::study_prony(in, 3000),
      study::study_fft(in, false),           study::study_fft(in, true),
      study::study_xspec(in, 50000, false),  study::study_xspec(in, 50000, true)};
  std::printf("10 %% noise, seed 1\n%s", study::format_table(rows).c_str());
  // Mode 3 (79/95 kHz) is well determined: within the target with 1000 and 3000 samples.
  expect_mode(rows[0], 2, 2e-3);
  expect_mode(rows[1], 2, 2e-3);
  // |Z| within 1 dB away from the peaks with 3000 samples.
  EXPECT_LT(rows[1].max_db_err, 1.0);
  // The raw FFT of a step held to the record's end is garbage (V1(f_k) ≈ 0 off DC).
  EXPECT_GT(rows[2].median_db_err, 3.0);
  // Modes 1-2 (51/54 kHz): the information limit is above the target.
  const auto crb3000 = pole_crb_rel(0.10, 3000), crb1000 = pole_crb_rel(0.10, 1000);
  ASSERT_EQ(crb3000.size(), 3u);
  std::printf("CRB (1σ) of the circuit poles, 10 %% noise: 3000 samples %.3f %% %.3f %% %.3f %%; "
              "1000 samples %.3f %% %.3f %% %.3f %%\n", 100 * crb3000[0], 100 * crb3000[1],
              100 * crb3000[2], 100 * crb1000[0], 100 * crb1000[1], 100 * crb1000[2]);
  EXPECT_GT(crb3000[0], 2e-3);
  EXPECT_GT(crb3000[1], 2e-3);
  EXPECT_LT(crb3000[2], 2e-3 / 3);
}

// 1 % noise (S/N 40 dB): every target met with 3000 samples.
TEST(Chapter5Study, OnePercentNoiseMeetsTargetsWith3000Samples) {
  const auto in = chapter5_input(0.01, 2, 1);
  const auto r = study::study_prony(in, 3000);
  std::printf("1 %% noise, seed 2\n%s", study::format_table({r}).c_str());
  for (std::size_t m = 0; m < 3; ++m) expect_mode(r, m, 2e-3);
  EXPECT_LT(r.max_db_err, 1.0);
  EXPECT_NEAR(double(r.order), 8.0, 2.0);
}

// 0.1 % noise with 1000 samples: |Z| within 1 dB, mode 3 within target; the
// 51/54 kHz pair still carries a CRB of ≈1.3 % at 1000 samples.
TEST(Chapter5Study, PerMilleNoiseWith1000Samples) {
  const auto in = chapter5_input(0.001, 3, 1);
  const auto r = study::study_prony(in, 1000);
  std::printf("0.1 %% noise, seed 3\n%s", study::format_table({r}).c_str());
  expect_mode(r, 2, 2e-3);
  EXPECT_LT(r.max_db_err, 1.0);
  EXPECT_GT(pole_crb_rel(0.001, 1000)[0], 2e-3 / 3);
}

}  // namespace
