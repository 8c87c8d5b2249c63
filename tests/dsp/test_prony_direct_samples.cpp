// Prony-SS with the first samples taken as recorded (PronyImpedanceOptions::
// direct_samples). Truth: the two-mode port of test_prony_ramp_onset plus two
// modes above the band (250 and 450 kHz, Rayleigh-damped: ζ ≈ 0.08 and 0.14,
// gone within ~15 µs), driven through R1 by a ramped exp_decay; its impedance
// is known in closed form. The fit is given the in-band order (6: the drive,
// the R1·C pole, two modes), as a noise-set order would be: the fast modes'
// transient is then either fitted by the in-band poles from t = 0 (their tails
// missing from V2, the residues biased) or integrated as recorded.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <vector>

#include "dsp/prony_impedance.hpp"
#include "model/port_model.hpp"
#include "model/transient.hpp"

namespace {
using namespace piezo;
constexpr double kFs = 1e7, kR1 = 3140.0, kTwoPi = 2 * M_PI;

model::ModalPortModel port_with_modes_above_the_band() {
  model::ModalPortModel p;
  p.c_clamped = 10e-9;
  for (double f : {50e3, 80e3, 250e3, 450e3}) {
    model::PortMode m;
    m.omega = kTwoPi * f;
    m.participation = std::sqrt(0.05 * p.c_clamped) * m.omega;
    m.kappa = m.omega * m.omega;
    p.modes.push_back(m);
  }
  return p;
}

TEST(PronyDirectSamples, ModesAboveTheBandEnterAsRecorded) {
  const auto port = port_with_modes_above_the_band();
  const model::RayleighDamping damping{0.0, 1e-7};
  model::DividerCircuit circuit;
  circuit.r1_ohm = kR1;
  const std::size_t pre = 50, n = pre + 6000;
  std::vector<double> v1(n, 0.0);
  for (std::size_t k = pre; k < n; ++k) v1[k] = std::exp(-3000.0 * double(k - pre) / kFs);
  const auto v2 = model::simulate_divider(port, damping, circuit, v1, kFs);
  const dsp::DividerRecord rec{v1, v2, kFs, kR1, pre, std::nullopt};
  auto truth = [&](double f) {
    return 1.0 / (std::complex<double>(0, kTwoPi * f) * port.charge_per_volt(kTwoPi * f, damping));
  };
  double err[2] = {0, 0};
  for (int direct : {0, 1}) {
    dsp::PronyImpedanceOptions o;
    o.ramp_onset = true;
    o.prony.order = 6;
    o.prony.band_hz = 120e3;  // D = 16: the Hankel step sees 0 … 250 kHz
    if (direct) o.direct_samples = dsp::PronyImpedanceOptions::kDirectFilterLength;
    const auto m = dsp::fit_prony_impedance(rec, o);
    EXPECT_EQ(m.direct_residual.rows(), direct ? 160 : 0);
    for (double f = 2e3; f <= 120e3; f += 500.0)
      err[direct] = std::max(err[direct], std::abs(m.z(f) / truth(f) - 1.0));
  }
  std::printf("max |Z/Z_true - 1| over 2-120 kHz, order 6: pole model from t = 0 %.2e, "
              "first 160 samples as recorded %.2e\n", err[0], err[1]);
  // Measured: 1.5e-2 from t = 0, 1.6e-3 with the direct samples (what is left:
  // the fast modes' tails beyond 16 µs, fitted by the in-band poles).
  EXPECT_LT(err[1], 3e-3);
  EXPECT_GT(err[0], 4 * err[1]);
}

}  // namespace
