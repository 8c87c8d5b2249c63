// Direct FFT ratio and averaged cross spectra: exact agreement with the analytic
// finite-record DFT of the divider signals, estimator identities on noise-free
// data, and noise averaging.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "bvd_model.hpp"
#include "dsp/cross_spectra.hpp"
#include "dsp/fft_ratio.hpp"

namespace {
using namespace piezo;
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// DFT bin k of x[n] = Σ r z^n, n = 0..N−1, in closed form.
cd dft(const bvd::ExpSum& x, double fs, std::size_t n, std::size_t k) {
  const cd w = std::exp(cd(0, -kTwoPi * double(k) / double(n)));
  cd acc = 0;
  for (std::size_t p = 0; p < x.lambda.size(); ++p) {
    const cd z = std::exp(x.lambda[p] / fs);
    acc += x.residue[p] * (1.0 - std::pow(z, double(n))) / (1.0 - z * w);
  }
  return acc;
}

struct Case {
  bvd::Bvd model = bvd::tube_bvd_rayleigh(1e-7);
  bvd::DividerResponse resp = bvd::divider_response(model, 3140.0, 1.0, 3000.0);
  double fs = 1e7;
  std::size_t n = 20000;
  std::vector<double> v1 = bvd::sample(resp.v1, fs, n), v2 = bvd::sample(resp.v2, fs, n);
};

TEST(FftRatio, MatchesClosedFormDft) {
  const Case c;
  dsp::FftRatioOptions o;
  o.difference = false;
  o.fmax_hz = 200e3;
  const auto r = dsp::impedance_fft({c.v1, c.v2, c.fs, 3140.0, 0, {}}, o);
  double worst = 0;
  for (Eigen::Index q = 0; q < r.f_hz.size(); ++q) {
    const auto k = static_cast<std::size_t>(std::llround(r.f_hz[q] * double(c.n) / c.fs));
    const cd x1 = dft(c.resp.v1, c.fs, c.n, k), x2 = dft(c.resp.v2, c.fs, c.n, k);
    worst = std::max(worst, std::abs(r.z_ohm[q] / (3140.0 * x2 / (x1 - x2)) - 1.0));
  }
  EXPECT_LT(worst, 1e-8);
  EXPECT_EQ(r.samples_used, c.n);
  EXPECT_DOUBLE_EQ(r.f_hz[0], c.fs / double(c.n));
}

// With differencing (the default), bin k holds DFT(Δx)[k] = (1 − W^k)·X[k] + x[N−1]
// for x[−1] = 0 — checked in closed form.
TEST(FftRatio, DifferencedMatchesClosedForm) {
  const Case c;
  dsp::FftRatioOptions o;
  o.fmax_hz = 200e3;
  const auto r = dsp::impedance_fft({c.v1, c.v2, c.fs, 3140.0, 0, {}}, o);
  double worst = 0;
  for (Eigen::Index q = 0; q < r.f_hz.size(); ++q) {
    const auto k = static_cast<std::size_t>(std::llround(r.f_hz[q] * double(c.n) / c.fs));
    const cd g = 1.0 - std::exp(cd(0, -kTwoPi * double(k) / double(c.n)));
    const cd x1 = g * dft(c.resp.v1, c.fs, c.n, k) + c.v1.back();
    const cd x2 = g * dft(c.resp.v2, c.fs, c.n, k) + c.v2.back();
    worst = std::max(worst, std::abs(r.z_ohm[q] / (3140.0 * x2 / (x1 - x2)) - 1.0));
  }
  EXPECT_LT(worst, 1e-8);
}

// σ of the differenced ratio per bin against 300 noise realizations, with the
// last sample as recorded and from a fit to the last 1000: at the
// lowest bins the last sample's noise, which the difference leaves whole in
// every bin, is most of it (|1 − e^{−jθ}|²·n ≪ 1 below ~11 kHz here); the
// first-difference gain alone gave 0.045 of the scatter at 500 Hz, 0.18 at
// 2 kHz, 0.69 at 10 kHz.
class FftRatioSigma : public ::testing::TestWithParam<std::size_t> {};

TEST_P(FftRatioSigma, DifferencedSigmaMatchesTheScatter) {
  const Case c;
  dsp::FftRatioOptions o;
  o.fmin_hz = 400;
  o.fmax_hz = 60e3;
  o.end_fit_samples = GetParam();
  const dsp::DividerRecord clean{c.v1, c.v2, c.fs, 3140.0, 0, {}};
  const auto r0 = dsp::impedance_fft(clean, o);
  const std::vector<Eigen::Index> bins{0, 1, 3, 19, 99};  // 0.5, 1, 2, 10, 50 kHz
  std::vector<double> var(bins.size(), 0.0), sig(bins.size(), 0.0);
  constexpr int kRuns = 300;
  for (int s = 0; s < kRuns; ++s) {
    const auto v1 = bvd::add_noise(c.v1, 0.005, 1000 + 2 * std::uint64_t(s));
    const auto v2 = bvd::add_noise(c.v2, 0.005, 1001 + 2 * std::uint64_t(s));
    const auto r = dsp::impedance_fft({v1, v2, c.fs, 3140.0, 0, {}}, o);
    for (std::size_t b = 0; b < bins.size(); ++b) {
      var[b] += std::norm(r.z_ohm[bins[b]] - r0.z_ohm[bins[b]]) / kRuns;
      sig[b] += r.z_sigma_ohm[bins[b]] / kRuns;
    }
  }
  for (std::size_t b = 0; b < bins.size(); ++b) {
    const double ratio = sig[b] / std::sqrt(var[b]);
    std::printf("%.1f kHz: sigma %.4g, scatter %.4g (ratio %.3f)\n", r0.f_hz[bins[b]] / 1e3, sig[b],
                std::sqrt(var[b]), ratio);
    EXPECT_GT(ratio, 0.8) << r0.f_hz[bins[b]];
    EXPECT_LT(ratio, 1.25) << r0.f_hz[bins[b]];
  }
  // The last sample from the fit to the last 1000: measured scatter at 500 Hz
  // 5053 Ω as recorded, 535 Ω from the fit (about 3/√1000 of it).
  if (GetParam() == 1000) {
    EXPECT_LT(std::sqrt(var[0]), 700.0);
  } else {
    EXPECT_GT(std::sqrt(var[0]), 3000.0);
  }
}

INSTANTIATE_TEST_SUITE_P(EndFit, FftRatioSigma, ::testing::Values(std::size_t(0), std::size_t(1000)));

TEST(CrossSpectra, NoiseFreeEstimatorsCoincide) {
  const Case c;
  std::vector<dsp::DividerRecord> recs(3, {c.v1, c.v2, c.fs, 3140.0, 0, {}});
  dsp::CrossSpectraOptions o;
  o.window = {dsp::WindowKind::Rectangular, 0};
  o.overlap = 0;
  o.difference = false;
  const auto cs = dsp::cross_spectra(recs, o);
  EXPECT_EQ(cs.segments, 3u);
  dsp::FftRatioOptions fo;
  fo.difference = false;
  const auto fr = dsp::impedance_fft(recs[0], fo);
  for (Eigen::Index k = 1; k < 2000; ++k) {
    EXPECT_NEAR(cs.coherence[k], 1.0, 1e-9);
    EXPECT_LT(std::abs(cs.h1[k] / cs.h2[k] - 1.0), 1e-9);
    EXPECT_LT(std::abs(cs.h161[k] / cs.h1[k] - 1.0), 1e-9);
    const cd z = 3140.0 * cs.h1[k] / (1.0 - cs.h1[k]);
    EXPECT_LT(std::abs(z / fr.z_ohm[k - 1] - 1.0), 1e-9);
  }
}

TEST(CrossSpectra, WelchSegmentCount) {
  const Case c;
  dsp::CrossSpectraOptions o;
  o.segment = 4000;
  o.overlap = 0.5;
  const dsp::DividerRecord rec{c.v1, c.v2, c.fs, 3140.0, 0, {}};
  const auto cs = dsp::cross_spectra({&rec, 1}, o);
  EXPECT_EQ(cs.segments, 9u);  // (20000 − 4000)/2000 + 1
  EXPECT_EQ(cs.f_hz.size(), 2001);
  o.segment = 30000;
  EXPECT_THROW(dsp::cross_spectra({&rec, 1}, o), std::invalid_argument);
}

// Output noise (on v2 only) averages out of H1: 40 records beat 1 record by
// about √40; the coherence-based σ tracks the actual error within a factor 3.
TEST(CrossSpectra, AveragingReducesNoiseAndSigmaIsCalibrated) {
  const Case c;
  std::vector<std::vector<double>> v2n;
  for (std::uint64_t s = 0; s < 40; ++s) v2n.push_back(bvd::add_noise(c.v2, 0.02, 77 + s));
  std::vector<dsp::DividerRecord> recs;
  for (const auto& v : v2n) recs.push_back({c.v1, v, c.fs, 3140.0, 0, {}});
  dsp::CrossSpectraOptions o;
  o.window = {dsp::WindowKind::Rectangular, 0};
  o.overlap = 0;
  o.estimator = dsp::SpectralEstimator::H1;
  o.fmin_hz = 1e3;
  o.fmax_hz = 120e3;
  auto rms_err = [&](const dsp::ImpedanceResult& r, double& sigma_rms) {
    double e = 0, s = 0;
    for (Eigen::Index q = 0; q < r.f_hz.size(); ++q) {
      const cd zt = c.model.impedance_at(r.f_hz[q]);
      // the FFT's own discretisation bias is removed by comparing with the noise-free estimate
      e += std::norm(r.z_ohm[q] - zt) / std::norm(zt);
      s += std::pow(r.z_sigma_ohm[q] / std::abs(zt), 2);
    }
    sigma_rms = std::sqrt(s / double(r.f_hz.size()));
    return std::sqrt(e / double(r.f_hz.size()));
  };
  const dsp::DividerRecord clean{c.v1, c.v2, c.fs, 3140.0, 0, {}};
  const auto r0 = dsp::impedance_xspec({&clean, 1}, o);
  const auto r1 = dsp::impedance_xspec({recs.data(), 1}, o);
  const auto r40 = dsp::impedance_xspec(recs, o);
  double s0, s1, s40;
  const double bias = rms_err(r0, s0);
  const double e1 = rms_err(r1, s1), e40 = rms_err(r40, s40);
  EXPECT_LT(bias, 0.05);
  EXPECT_GT(e1, 3.0 * std::max(e40, bias));
  const double noise40 = std::sqrt(std::max(0.0, e40 * e40 - bias * bias));
  EXPECT_GT(s40 / noise40, 1.0 / 3.0);
  EXPECT_LT(s40 / noise40, 3.0);
}

}  // namespace
