// The voltage-drive → charge path (dsp/prony_charge.hpp, seed eqs 111–116) and
// the seed's §5.1.1 case on our FE tube (fe_charge.hpp): the published APC850
// tube's port model, NO damping (β = 0), driven by 500·e^{−0.001 t} V from
// t = 0, its electrode charge at 10 MS/s; Prony-SS on the first 1000 samples
// (100 µs, the seed's "initial segment from 0 to 1e-4 s") with the seed's
// 500 × 500 Hankel matrix, Z = V/(sQ) against the FE's stepped-harmonic |Z|
// (the port model's Z(jω) on the seed's 200 Hz grid, which the estimator never sees).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "dsp/fft.hpp"
#include "dsp/prony_charge.hpp"
#include "fe_charge.hpp"

namespace {
using namespace piezo;

const fe5::ChargeData& clean() {
  static const fe5::ChargeData d = fe5::charge_data(fe5::chapter5(), 0.0);
  return d;
}

// The seed's grid (0–120 kHz, 200 Hz; from 200 Hz: Z(0) is infinite).
Eigen::VectorXd seed_grid() { return dsp::make_grid(200.0, 120e3, 200.0); }

struct DbError {
  double max_db = 0, f_at = 0;
  std::size_t scored = 0;
};

// |20·log10(|Z_est|/|Z_true|)| over the grid, away from the peaks: outside
// ±peak_exclusion_rel (1.5 %) of every true |Z| extremum, the divider study's
// definition (impedance_study.hpp). With β = 0 the true |Z| is 0 or ∞ at the
// extrema, so any frequency error, however small, makes the dB error unbounded
// there; 1.5 % keeps each excluded band at 0.75–1.4 kHz, 4–7 bins of the grid.
DbError db_error(const study::StudyInput& in, const dsp::ImpedanceResult& r) {
  DbError e;
  for (Eigen::Index k = 0; k < r.f_hz.size(); ++k) {
    const double f = r.f_hz[k];
    if (study::near_feature(in, f)) continue;
    const double db = std::abs(20.0 * std::log10(std::abs(r.z_ohm[k]) / std::abs(in.z_true(f))));
    ++e.scored;
    if (db > e.max_db) {
      e.max_db = db;
      e.f_at = f;
    }
  }
  return e;
}

dsp::PronyOptions seed_hankel() {
  dsp::PronyOptions o;
  o.rows = 500;
  o.cols = 500;
  o.max_order = 100;  // the seed's Fig. 27 shows the first 100 singular values
  o.svd = dsp::SvdMethod::Full;
  return o;
}

Eigen::VectorXd first(const std::vector<double>& x, std::size_t n) {
  return Eigen::Map<const Eigen::VectorXd>(x.data(), static_cast<Eigen::Index>(n));
}

}  // namespace

TEST(PronyCharge, LargestDropOrder) {
  Eigen::VectorXd s(6);
  s << 10, 8, 7, 0.01, 0.009, 0.008;
  EXPECT_EQ(dsp::largest_drop_order(s, 100), 3u);
  EXPECT_EQ(dsp::largest_drop_order(s, 2), 1u) << "only drops among the first max_order + 1 count";
  s << 1, 0.5, 0.4, 0.3, 1e-15, 1e-30;  // numerical rank 4: rounding below it does not count
  EXPECT_EQ(dsp::largest_drop_order(s, 100), 4u);
  EXPECT_THROW(dsp::largest_drop_order(Eigen::VectorXd::Ones(1), 5), std::invalid_argument);
}

// The exact pole–residue sum of fe_charge.cpp (from the port model) and the FE
// transient of model/transient.cpp are the same charge, built independently.
// The transient is exact to the port model for piecewise-linear input; the
// drive's curvature between samples is (λvΔt)²/8·γv ≈ 6e-19 V, so what is left
// is the rounding of the matrix exponential over 5e4 steps.
TEST(PronyCharge, TransientIsThePoleResidueSum) {
  for (double beta : {0.0, 1e-7}) {
    const auto d = fe5::charge_data(fe5::chapter5(), beta);
    double worst = 0, qmax = 0;
    for (std::size_t k = 0; k < 3000; ++k) {
      worst = std::max(worst, std::abs(d.q[k] - d.q_exact(double(k) / d.sample_rate_hz)));
      qmax = std::max(qmax, std::abs(d.q[k]));
    }
    std::printf("measured: β = %g: max |q_transient − q_poles| = %.3g of max |q| %.3g C\n", beta,
                worst / qmax, qmax);
    EXPECT_LT(worst, 1e-9 * qmax) << beta;
  }
}

// §5.1.1: noise-free, β = 0, 1000 samples, 500 × 500 Hankel, the seed's
// largest-drop rule. The charge is exactly 1 + 2·14 exponentials (the drive
// pole and the 14 modes of the 24 + residual that couple to the electrode,
// 50 kHz to the 1.15 MHz residual mode), so the largest drop is the numerical
// rank, 29, and the fit is exact up to rounding. The noise-floor rule (the
// house default, eqs 162–163) is printed for comparison: on noise-free data
// its noise estimate (6th differences) takes the undamped 1.15 MHz residual
// mode for noise and stops early (order 15), which is why the seed's rule is
// the one this case asserts.
TEST(PronyCharge, Seed511CleanMatchesSteppedHarmonic) {
  const auto& d = clean();
  const study::StudyInput in = fe5::charge_study_input(d);
  const Eigen::VectorXd q = first(d.q, 1000);
  for (auto rule : {dsp::OrderRule::LargestDrop, dsp::OrderRule::NoiseFloor}) {
    auto o = seed_hankel();
    o.order_rule = rule;
    const auto m = dsp::fit_prony_charge(q, d.sample_rate_hz, d.drive, o);
    const auto r = dsp::impedance_from_charge(m, seed_grid());
    const DbError e = db_error(in, r);
    const bool seed_rule = rule == dsp::OrderRule::LargestDrop;
    std::printf("measured (%s rule): order %zu, max |Z| error away from the peaks %.3g dB at %.1f kHz (%zu bins)\n",
                seed_rule ? "largest-drop" : "noise-floor", m.fit.order, e.max_db, e.f_at / 1e3, e.scored);
    if (!seed_rule) continue;
    EXPECT_EQ(m.fit.order, 2 * (d.poles.size() - 1) + 1);
    EXPECT_LT(e.max_db, 0.1);
    EXPECT_GT(e.scored, 500u);
  }
}

// The recorded drive decomposed as well (one exponential) gives the same Z.
TEST(PronyCharge, RecordedDriveDecomposed) {
  const auto& d = clean();
  const study::StudyInput in = fe5::charge_study_input(d);
  std::vector<double> v(1000);
  for (std::size_t k = 0; k < v.size(); ++k)
    v[k] = d.drive.amplitude_v * std::exp(d.drive.pole_per_s * double(k) / d.sample_rate_hz);
  dsp::PronyOptions vo;
  vo.order = 1;
  auto o = seed_hankel();
  o.order_rule = dsp::OrderRule::LargestDrop;
  const auto m = dsp::fit_prony_charge(first(d.q, 1000), first(v, 1000), d.sample_rate_hz, o, vo);
  ASSERT_TRUE(m.drive_fit);
  const auto r = dsp::impedance_from_charge(m, seed_grid());
  const DbError e = db_error(in, r);
  std::printf("measured (recorded drive): drive pole %.4g 1/s, max |Z| error %.3g dB\n",
              m.drive_fit->lambda[0].real(), e.max_db);
  EXPECT_LT(e.max_db, 0.1);
}

// Fig. 25's third curve: the direct FFT ratio of the same 1000 samples,
// Z(f_k) = V_k/(j2πf_k Q_k), zero-padded to the 200 Hz grid (50 000 points).
// A 100 µs record resolves 10 kHz, the mode pair is 3.1 kHz apart and with
// β = 0 the charge does not decay, so the rectangular window's leakage rules
// the ratio: the seed's "FFT worse" holds by orders of magnitude against
// Prony-SS's 5e-11 dB above (the bound 1 dB is 1e10 times that).
TEST(PronyCharge, Seed511FftRatioOfTheSameSamplesIsWorse) {
  const auto& d = clean();
  const study::StudyInput in = fe5::charge_study_input(d);
  constexpr std::size_t n = 1000, nfft = 50000;  // fs / nfft = 200 Hz
  std::vector<double> v(n);
  for (std::size_t k = 0; k < n; ++k)
    v[k] = d.drive.amplitude_v * std::exp(d.drive.pole_per_s * static_cast<double>(k) / d.sample_rate_hz);
  dsp::RealFft fft(nfft);
  std::vector<std::complex<double>> vk(fft.bins()), qk(fft.bins());
  fft.forward(v.data(), n, vk.data());
  fft.forward(d.q.data(), n, qk.data());
  DbError e;
  std::vector<double> all;
  for (std::size_t k = 1; k < fft.bins(); ++k) {
    const double f = static_cast<double>(k) * d.sample_rate_hz / static_cast<double>(nfft);
    if (f > 120e3) break;
    if (study::near_feature(in, f)) continue;
    const std::complex<double> z = vk[k] / (std::complex<double>(0, 2 * std::numbers::pi * f) * qk[k]);
    const double db = std::abs(20.0 * std::log10(std::abs(z) / std::abs(in.z_true(f))));
    ++e.scored;
    all.push_back(db);
    if (db > e.max_db) e.max_db = db, e.f_at = f;
  }
  std::nth_element(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(all.size() / 2), all.end());
  std::printf("measured: FFT ratio of the first %zu samples, |Z| error away from the peaks: median %.3g dB, "
              "max %.3g dB at %.1f kHz (%zu bins)\n", n, all[all.size() / 2], e.max_db, e.f_at / 1e3, e.scored);
  EXPECT_GT(e.scored, 500u);
  EXPECT_GT(e.max_db, 1.0);
}
