// The simulated bench's generic channel-2 stage (acquisition/channel2_response):
// a catalogue term applied to a record, against the analytic answer.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <vector>

#include "acquisition/channel2_response.hpp"

using namespace piezo;

namespace {
std::vector<double> gaussian(std::size_t n, double dt, double t0, double width) {
  std::vector<double> v(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double u = (double(k) * dt - t0) / width;
    v[k] = std::exp(-0.5 * u * u);
  }
  return v;
}
}  // namespace

TEST(Channel2Response, ALateSamplingTermDelaysTheRecord) {
  // exp(−jωτ) on a pulse well inside the record: the pulse τ later, to the
  // FFT's rounding (the pulse's spectrum is below 1e-30 at Nyquist).
  const std::size_t n = 4000;
  const double dt = 1e-6, tau = 3.7e-6, t0 = 1.5e-3, width = 20e-6;
  std::vector<double> v = gaussian(n, dt, t0, width);
  acq::apply_channel2_response(v, dt, [tau](double w) { return std::exp(std::complex<double>(0, -w * tau)); });
  const std::vector<double> want = gaussian(n, dt, t0 + tau, width);
  double worst = 0;
  for (std::size_t k = 0; k < n; ++k) worst = std::max(worst, std::fabs(v[k] - want[k]));
  EXPECT_LT(worst, 1e-12);
}

TEST(Channel2Response, ALowPassTermIsCausalAndKeepsDc) {
  // 1/(1 + jω/ωc) on a step: 1 − e^{−t/RC} after it, and nothing before it
  // (the zero padding keeps the response's tail out of the record's start).
  const std::size_t n = 20000;
  const double dt = 1e-7, rc = 2e-6, t_step = 0.5e-3;
  std::vector<double> v(n);
  for (std::size_t k = 0; k < n; ++k) v[k] = double(k) * dt >= t_step ? 1.0 : 0.0;
  acq::apply_channel2_response(v, dt, [rc](double w) { return 1.0 / std::complex<double>(1.0, w * rc); });
  // Away from the jump and the record's end (the step sampled at dt rings
  // with the discrete transform's Gibbs tail, a few samples wide).
  EXPECT_LT(std::fabs(v[100]), 1e-3);
  for (double t : {t_step + 2e-6, t_step + 5e-6, t_step + 20e-6}) {
    const auto k = static_cast<std::size_t>(std::lround(t / dt));
    EXPECT_NEAR(v[k], 1.0 - std::exp(-(double(k) * dt - t_step) / rc), 0.02) << t;
  }
}

TEST(Channel2Response, NoGenericTermForTheCatalogueOwnEffects) {
  // Every channel-2 effect of today's catalogue has an element of its own in
  // the simulated DAQ (skew, gain): the generic stage must not apply it twice.
  model::EffectSet fx;
  fx.channel_skew_s = 1e-7;
  fx.channel_gain = 0.01;
  EXPECT_FALSE(acq::channel2_response(fx));
  EXPECT_FALSE(acq::channel2_response(model::EffectSet{}));
}
