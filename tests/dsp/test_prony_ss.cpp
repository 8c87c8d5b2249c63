// Prony-SS decomposition and the Laplace-domain impedance: exact recovery on
// noise-free sums of exponentials and on the analytic divider, order selection
// on noisy data, and refusals with a clear message.
#include "dsp/prony_ss.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <numbers>
#include <random>

#include "bvd_model.hpp"
#include "dsp/prony_impedance.hpp"

namespace {
using namespace piezo;
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Largest relative distance from each true pole to the nearest estimated one.
double pole_error(const std::vector<cd>& truth, const Eigen::VectorXcd& est) {
  double worst = 0;
  for (cd t : truth) {
    double best = 1e300;
    for (Eigen::Index k = 0; k < est.size(); ++k) best = std::min(best, std::abs(est[k] - t) / std::abs(t));
    worst = std::max(worst, best);
  }
  return worst;
}

// Two signals on five shared poles (one real, two pairs), 1 MS/s.
struct Synthetic {
  std::vector<cd> poles{cd(-2000, 0), cd(-300, kTwoPi * 21e3), cd(-300, -kTwoPi * 21e3),
                        cd(-900, kTwoPi * 47e3), cd(-900, -kTwoPi * 47e3)};
  std::vector<std::vector<cd>> res{{cd(1.0, 0), cd(0.4, 0.2), cd(0.4, -0.2), cd(0.1, -0.3), cd(0.1, 0.3)},
                                   {cd(-0.5, 0), cd(0.05, 0.7), cd(0.05, -0.7), cd(0.2, 0), cd(0.2, 0)}};
  double fs = 1e6;
  Eigen::MatrixXd sample(Eigen::Index n) const {
    Eigen::MatrixXd y = Eigen::MatrixXd::Zero(n, 2);
    for (Eigen::Index k = 0; k < n; ++k)
      for (std::size_t j = 0; j < 2; ++j)
        for (std::size_t p = 0; p < poles.size(); ++p)
          y(k, static_cast<Eigen::Index>(j)) += (res[j][p] * std::exp(poles[p] * (double(k) / fs))).real();
    return y;
  }
  cd laplace(std::size_t j, cd s) const {
    cd a = 0;
    for (std::size_t p = 0; p < poles.size(); ++p) a += res[j][p] / (s - poles[p]);
    return a;
  }
};

class PronyNoiseFree : public ::testing::TestWithParam<dsp::SvdMethod> {};

// Acceptance: poles to 1e-8 relative, Y(jω) (and the ratio of two transforms,
// the form Z takes) equal to the analytic one to 1e-6 relative.
TEST_P(PronyNoiseFree, SumOfExponentialsPolesAndLaplace) {
  const Synthetic syn;
  dsp::PronyOptions o;
  o.svd = GetParam();
  o.rows = 60;
  o.cols = 340;
  const auto fit = dsp::prony_ss(syn.sample(400), syn.fs, o);
  EXPECT_EQ(fit.order, 5u);
  const double pe = pole_error(syn.poles, fit.lambda);
  EXPECT_LT(pe, 1e-8);
  double worst = 0, worst_ratio = 0;
  for (double f = 100; f <= 200e3; f *= 1.05) {
    const cd s(0, kTwoPi * f);
    for (int j = 0; j < 2; ++j)
      worst = std::max(worst, std::abs(dsp::laplace(fit, j, s) / syn.laplace(std::size_t(j), s) - 1.0));
    const cd ratio = dsp::laplace(fit, 1, s) / dsp::laplace(fit, 0, s);
    worst_ratio = std::max(worst_ratio, std::abs(ratio / (syn.laplace(1, s) / syn.laplace(0, s)) - 1.0));
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_LT(worst_ratio, 1e-6);
  std::printf("measured: pole error %.2e, Y(jw) error %.2e, ratio error %.2e\n", pe, worst, worst_ratio);
  // The reconstruction reproduces the samples.
  EXPECT_LT(fit.residual_rms.maxCoeff(), 1e-10);
}

INSTANTIATE_TEST_SUITE_P(Svd, PronyNoiseFree,
                         ::testing::Values(dsp::SvdMethod::Full, dsp::SvdMethod::Randomized));

// The divider with the analytic BVD: lab drive (1 V, 3000/s), 10 MS/s, pretrigger
// with a DAQ offset. v1, v2 and i share the circuit poles plus the drive pole.
struct DividerCase {
  bvd::Bvd model = bvd::tube_bvd_q(200);
  bvd::DividerResponse resp = bvd::divider_response(model, 3140.0, 1.0, 3000.0);
  std::vector<double> v1, v2;
  DividerCase(std::size_t n, std::size_t pre, double offset) {
    v1 = bvd::sample(resp.v1, 1e7, n, pre);
    v2 = bvd::sample(resp.v2, 1e7, n, pre);
    for (auto& v : v1) v += offset;
    for (auto& v : v2) v += offset;
  }
  dsp::DividerRecord record(std::size_t pre) const { return {v1, v2, 1e7, 3140.0, pre, {}}; }
  double z_error(const dsp::PronyImpedance& m) const {
    double worst = 0;
    for (double f = 1e3; f <= 120e3; f += 250)
      worst = std::max(worst, std::abs(m.z(f) / model.impedance_at(f) - 1.0));
    return worst;
  }
};

TEST(PronyDivider, NoiseFreeFullRateMatchesAnalyticZ) {
  const DividerCase c(1100, 100, 0.0);
  dsp::PronyImpedanceOptions o;
  o.prony.decimation = 1;
  const auto m = dsp::fit_prony_impedance(c.record(100), o);
  EXPECT_EQ(m.fit.order, 8u);
  EXPECT_LT(pole_error(c.resp.v2.lambda, m.fit.lambda), 1e-8);
  EXPECT_LT(c.z_error(m), 1e-6);
  std::printf("measured: pole error %.2e, Z(jw) error %.2e\n", pole_error(c.resp.v2.lambda, m.fit.lambda), c.z_error(m));
}

TEST(PronyDivider, NoiseFreeDecimatedWithOffsetAndSkip) {
  const DividerCase c(3100, 100, 0.013);  // DAQ offset removed over the pretrigger
  dsp::PronyImpedanceOptions o;
  o.prony.band_hz = 120e3;  // D = 16
  o.prony.skip_samples = 5;  // residues still referred to t = 0
  const auto m = dsp::fit_prony_impedance(c.record(100), o);
  EXPECT_EQ(m.fit.decimation, 16u);
  EXPECT_EQ(m.fit.order, 8u);
  EXPECT_LT(pole_error(c.resp.v2.lambda, m.fit.lambda), 1e-8);
  EXPECT_LT(c.z_error(m), 1e-6);
  std::printf("measured: pole error %.2e, Z(jw) error %.2e\n", pole_error(c.resp.v2.lambda, m.fit.lambda), c.z_error(m));
}

// The one-sided transform needs the fit to start at the drive step: a pretrigger
// misplaced by 10 samples (1 µs) must be visible, not absorbed.
TEST(PronyDivider, StepAtTimeZeroMatters) {
  const DividerCase c(3100, 100, 0.0);
  dsp::PronyImpedanceOptions o;
  o.prony.band_hz = 120e3;
  EXPECT_GT(c.z_error(dsp::fit_prony_impedance(c.record(90), o)), 1e-2);
}

TEST(PronyDivider, ImpedanceResultCarriesFeaturesAndSummary) {
  const DividerCase c(3100, 0, 0.0);
  dsp::PronyImpedanceOptions o;
  o.prony.band_hz = 120e3;
  const auto r = dsp::impedance_prony(c.record(0), dsp::make_grid(1e3, 120e3, 500), o);
  ASSERT_TRUE(r.prony);
  EXPECT_EQ(r.prony->order, 8u);
  EXPECT_DOUBLE_EQ(r.prony->singular_values_normalized.front(), 1.0);
  EXPECT_TRUE(std::is_sorted(r.prony->singular_values_normalized.rbegin(),
                             r.prony->singular_values_normalized.rend()));
  ASSERT_EQ(r.features.resonances.size(), 3u);
  ASSERT_EQ(r.features.antiresonances.size(), 3u);
  const auto truth = dsp::find_features([&](double f) { return c.model.impedance_at(f); }, 1e3, 120e3, 20.0);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR(r.features.resonances[k].extremum_hz / truth.resonances[k].f_hz, 1.0, 1e-7);
    EXPECT_NEAR(r.features.antiresonances[k].extremum_hz / truth.antiresonances[k].f_hz, 1.0, 1e-7);
    // The modal (natural) frequency of the zero of Z is the branch's series
    // resonance 1/√(LC) exactly (Y's pole s² LC + sRC + 1 = 0 has |s|² = 1/LC),
    // unlike the |Z| minimum, which damping pulls away from it.
    const auto& b = c.model.branches[k];
    EXPECT_NEAR(r.features.resonances[k].f_hz * 2 * M_PI * std::sqrt(b.L * b.C), 1.0, 1e-7);
    // The anti-resonance: |s| of the zero of the true admittance next to the |Z| maximum.
    std::complex<double> s0(0, 2 * M_PI * truth.antiresonances[k].f_hz);
    for (int it = 0; it < 50; ++it) {
      const std::complex<double> h(1e-3, 0);
      const auto y = c.model.admittance(s0);
      s0 -= y / ((c.model.admittance(s0 + h) - c.model.admittance(s0 - h)) / (2.0 * h));
    }
    EXPECT_NEAR(r.features.antiresonances[k].f_hz / (std::abs(s0) / (2 * M_PI)), 1.0, 1e-7);
  }
  // Im(1/Z) = ω(C + Dω²) fitted below 0.3·f_r1; the BVD's exact value is C0 + ΣC_n.
  EXPECT_NEAR(r.features.capacitance_f / c.model.static_capacitance(), 1.0, 1e-3);
  // Poles: the three circuit modes with ξ = a/|λ| (eq. 165).
  int modes = 0;
  for (const auto& p : r.prony->poles)
    if (p.freq_hz > 1e3) {
      ++modes;
      EXPECT_GT(p.damping_ratio, 0.0);
      EXPECT_LT(p.damping_ratio, 0.05);
    }
  EXPECT_EQ(modes, 3);
}

// Acceptance: automatic order within ±2 of the true order on noisy synthetic data.
TEST(PronyOrder, AutomaticWithinTwoOnNoisyData) {
  const Synthetic syn;
  const Eigen::MatrixXd clean = syn.sample(600);
  for (double level : {1e-3, 1e-2, 3e-2}) {
    for (std::uint64_t seed = 1; seed <= 5; ++seed) {
      std::mt19937_64 rng(seed);
      std::normal_distribution<double> nd(0.0, level);
      Eigen::MatrixXd y = clean;
      for (Eigen::Index i = 0; i < y.size(); ++i) y.data()[i] += nd(rng);
      const auto fit = dsp::prony_ss(y, syn.fs);
      EXPECT_NEAR(double(fit.order), 5.0, 2.0) << "noise " << level << " seed " << seed;
    }
  }
  // The divider at 1 % noise on v1 and v2 (true order 8).
  const DividerCase c(3000, 0, 0.0);
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const auto v1 = bvd::add_noise(c.v1, 0.01, seed), v2 = bvd::add_noise(c.v2, 0.01, seed + 50);
    dsp::PronyImpedanceOptions o;
    o.prony.band_hz = 120e3;
    const auto m = dsp::fit_prony_impedance({v1, v2, 1e7, 3140.0, 0, {}}, o);
    EXPECT_NEAR(double(m.fit.order), 8.0, 2.0) << "seed " << seed;
  }
}

TEST(PronyOrder, ManualOverride) {
  const Synthetic syn;
  dsp::PronyOptions o;
  o.order = 3;
  const auto fit = dsp::prony_ss(syn.sample(400), syn.fs, o);
  EXPECT_EQ(fit.order, 3u);
  EXPECT_FALSE(fit.order_automatic);
  EXPECT_EQ(fit.lambda.size(), 3);
}

// prony_ss_orders: each order from ONE decomposition equals a separate prony_ss
// at that order (the realization of order p is the leading p × p block of the
// largest one's). With the full SVD both use the same singular triplets, so
// the poles agree to rounding; an order above the Hankel rank is that entry's
// error, not an exception for the others.
TEST(PronyOrder, SeveralOrdersFromOneDecompositionMatchSeparateFits) {
  const Synthetic syn;
  Eigen::MatrixXd y = syn.sample(300);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> nd(0.0, 1e-3);
  for (Eigen::Index i = 0; i < y.size(); ++i) y.data()[i] += nd(rng);
  dsp::PronyOptions o;
  o.svd = dsp::SvdMethod::Full;
  const std::vector<std::size_t> orders{0, 3, 5, 9, 1000};
  const auto fits = dsp::prony_ss_orders(y, syn.fs, o, orders);
  ASSERT_EQ(fits.size(), orders.size());
  for (std::size_t i = 0; i + 1 < orders.size(); ++i) {
    ASSERT_TRUE(fits[i].fit) << fits[i].error;
    dsp::PronyOptions one = o;
    if (orders[i]) one.order = orders[i];
    const auto ref = dsp::prony_ss(y, syn.fs, one);
    ASSERT_EQ(fits[i].fit->order, ref.order);
    EXPECT_EQ(fits[i].fit->order_automatic, orders[i] == 0);
    std::vector<cd> truth(ref.lambda.data(), ref.lambda.data() + ref.lambda.size());
    EXPECT_LT(pole_error(truth, fits[i].fit->lambda), 1e-9) << "order " << orders[i];
  }
  EXPECT_FALSE(fits.back().fit);
  EXPECT_NE(fits.back().error.find("too small for order 1000"), std::string::npos) << fits.back().error;
}

// Refusals: a clear std::invalid_argument naming the function and the problem.
void expect_refusal(const std::function<void()>& f, const std::string& needle) {
  try {
    f();
    ADD_FAILURE() << "no exception, expected: " << needle;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(PronyRefusals, HankelTooSmallForOrder) {
  const Synthetic syn;
  dsp::PronyOptions o;
  o.order = 30;
  o.rows = 10;
  o.cols = 40;
  expect_refusal([&] { dsp::prony_ss(syn.sample(60), syn.fs, o); }, "too small for order 30");
}

TEST(PronyRefusals, OrderAboveNumericalRank) {
  const Synthetic syn;
  dsp::PronyOptions o;
  o.order = 12;  // the data have rank 5
  expect_refusal([&] { dsp::prony_ss(syn.sample(200), syn.fs, o); }, "numerical rank");
}

TEST(PronyRefusals, ConstantSignal) {
  Eigen::MatrixXd y = Eigen::MatrixXd::Constant(500, 1, 2.5);
  expect_refusal([&] { dsp::prony_ss(y, 1e6); }, "constant");
  const std::vector<double> v1(1000, 1.0), v2(1000, 1.0);
  expect_refusal([&] { dsp::fit_prony_impedance({v1, v2, 1e7, 3140, 0, {}}); }, "constant");
}

TEST(PronyRefusals, NoCurrent) {
  const DividerCase c(1000, 0, 0.0);
  expect_refusal([&] { dsp::fit_prony_impedance({c.v2, c.v2, 1e7, 3140, 0, {}}); }, "no current");
}

TEST(PronyRefusals, TooShort) {
  const Synthetic syn;
  expect_refusal([&] { dsp::prony_ss(syn.sample(6), syn.fs); }, "too short");
  const DividerCase c(3000, 0, 0.0);
  dsp::PronyImpedanceOptions o;
  o.prep.max_samples = 100;
  o.prony.band_hz = 20e3;  // D = 100: 100 samples cannot hold the decimation filter
  expect_refusal([&] { dsp::fit_prony_impedance(c.record(0), o); }, "too short");
  o.prep.max_samples = 5000;
  expect_refusal([&] { dsp::fit_prony_impedance(c.record(0), o); }, "the record has 3000");
}

TEST(PronyRefusals, Clipped) {
  DividerCase c(3000, 0, 0.0);
  const double top = *std::max_element(c.v2.begin(), c.v2.end()) * 0.8;
  for (auto& v : c.v2) v = std::min(v, top);  // converter pinned at full scale
  expect_refusal([&] { dsp::fit_prony_impedance(c.record(0)); }, "v2 is clipped");
}

TEST(PronyRefusals, NonFiniteAndBadRate) {
  Synthetic syn;
  Eigen::MatrixXd y = syn.sample(100);
  expect_refusal([&] { dsp::prony_ss(y, 0.0); }, "sample rate");
  y(5, 0) = std::nan("");
  expect_refusal([&] { dsp::prony_ss(y, 1e6); }, "NaN");
}

}  // namespace
