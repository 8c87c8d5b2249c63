// Seed chapter 5.1.2 on the analytic BVD divider: 10 MS/s, Rayleigh β = 1e-7,
// v1 = 500·e^{−0.001 t} for 5 ms, 10 % white noise on v1 and v2 (std(noise) =
// 0.1·std(clean channel over the 5 ms record)). Prony-SS with 1000 and 3000
// samples beside the direct FFT (one 5e4 record) and the cross spectra (20
// records of 5e4 samples). Tolerances are those of the acceptance criteria.
#include <gtest/gtest.h>

#include <cstdio>

#include "bvd_model.hpp"
#include "dsp/features.hpp"
#include "impedance_study.hpp"

namespace {
using namespace piezo;

study::StudyInput chapter5_input(std::uint64_t seed, std::size_t records) {
  const auto bvd_m = bvd::tube_bvd_rayleigh(1e-7);
  const auto resp = bvd::divider_response(bvd_m, 3140.0, 500.0, 1e-3);
  const double fs = 1e7;
  const std::size_t n = 50000;
  const auto v1c = bvd::sample(resp.v1, fs, n), v2c = bvd::sample(resp.v2, fs, n);
  study::StudyInput in;
  in.sample_rate_hz = fs;
  in.r1_ohm = 3140.0;
  for (std::size_t r = 0; r < records; ++r) {
    in.v1.push_back(bvd::add_noise(v1c, 0.10, seed * 1000 + 2 * r));
    in.v2.push_back(bvd::add_noise(v2c, 0.10, seed * 1000 + 2 * r + 1));
  }
  in.z_true = [bvd_m](double f) { return bvd_m.impedance_at(f); };
  const auto truth = dsp::find_features(in.z_true, 1e3, 120e3, 10.0);
  for (const auto& f : truth.resonances) in.true_resonances_hz.push_back(f.f_hz);
  for (const auto& f : truth.antiresonances) in.true_antiresonances_hz.push_back(f.f_hz);
  return in;
}

TEST(Chapter5Study, TruthHasThreeModes) {
  const auto in = chapter5_input(1, 1);
  ASSERT_EQ(in.true_resonances_hz.size(), 3u);
  ASSERT_EQ(in.true_antiresonances_hz.size(), 3u);
}

TEST(Chapter5Study, ComparisonTable) {
  const auto in = chapter5_input(1, 20);
  std::vector<study::StudyRow> rows{study::study_prony(in, 1000), study::study_prony(in, 3000),
                                    study::study_fft(in, false), study::study_fft(in, true),
                                    study::study_xspec(in, 50000, false), study::study_xspec(in, 50000, true)};
  std::printf("%s", study::format_table(rows).c_str());
}

}  // namespace
