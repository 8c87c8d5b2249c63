// The simulated bench's physics against independent references: the harmonic
// port model of the FE tube (frequency domain), the model's own uniform-step
// divider simulator (a second time integrator), and circuit algebra for the
// effects.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include "acquisition/divider_state_space.hpp"
#include "model/bench_response.hpp"
#include "model/material_presets.hpp"
#include "model/modal.hpp"
#include "model/transient.hpp"
#include "model/tube_model.hpp"
#include "tests/support/apc850_port.hpp"

using namespace piezo;
using cd = std::complex<double>;

namespace {
using test::apc850_port;
model::RayleighDamping beta7() { return {0.0, 1e-7}; }

cd tube_z(double w) {  // Z = V/I = 1/(jω·Q/V)
  return 1.0 / (cd(0, w) * apc850_port().charge_per_volt(w, beta7()));
}
}  // namespace

TEST(SimPhysics, TransferEqualsTheDividerOfTheHarmonicImpedance) {
  acq::BenchCircuit c;
  c.damping = beta7();
  acq::DividerStateSpace ss(apc850_port(), c);
  for (double f : {400.0, 10e3, 50e3, 50.29e3, 51.1e3, 79e3, 95e3, 150e3}) {
    double w = 2 * M_PI * f;
    cd z = tube_z(w), want = z / (z + c.r1_ohm);
    EXPECT_LT(std::abs(ss.transfer(w) - want) / std::abs(want), 1e-9) << f;  // same algebra, rounding only
  }
}

TEST(SimPhysics, CircuitEffectsFollowCircuitAlgebra) {
  acq::BenchCircuit c;
  c.damping = beta7();
  c.series_resistance_ohm = 12.0;
  c.parallel_capacitance_f = 150e-12;
  c.daq_input_resistance_ohm = 1e6;
  acq::DividerStateSpace ss(apc850_port(), c);
  for (double f : {1e3, 30e3, 50.5e3, 80e3, 120e3}) {
    double w = 2 * M_PI * f;
    cd zt = tube_z(w) + c.series_resistance_ohm;  // lead in series with the tube
    cd yshunt = cd(0, w * c.parallel_capacitance_f) + 1.0 / c.daq_input_resistance_ohm;
    cd znode = 1.0 / (1.0 / zt + yshunt);
    cd want = znode / (znode + c.r1_ohm);
    EXPECT_LT(std::abs(ss.transfer(w) - want) / std::abs(want), 1e-9) << f;
  }
}

TEST(SimPhysics, TimeDomainAgreesWithTheModelsUniformStepSimulator) {
  const double fs = 1e7;
  const int n = 20000;
  std::vector<double> v1(n), t(n);
  drivers::sim::PiecewiseLinear pl;
  for (int k = 0; k < n; ++k) {  // smooth burst (no jump), so both integrators see the same input
    t[k] = k / fs;
    double s = t[k] * 1e4;
    v1[k] = std::sin(2 * M_PI * 51e3 * t[k]) * (s < 1 ? s * s : std::exp(-3000 * (t[k] - 1e-4)));
    pl.t.push_back(t[k]);
    pl.v.push_back(v1[k]);
  }
  acq::BenchCircuit c;
  c.damping = beta7();
  acq::DividerStateSpace ss(apc850_port(), c);
  auto a = ss.simulate(pl, t);
  model::DividerCircuit mc;
  mc.r1_ohm = c.r1_ohm;
  auto b = model::simulate_divider(apc850_port(), beta7(), mc, v1, fs);
  double peak = 0, err = 0;
  for (int k = 0; k < n; ++k) {
    peak = std::max(peak, std::fabs(b[k]));
    err = std::max(err, std::fabs(a[k] - b[k]));
  }
  EXPECT_LT(err / peak, 1e-8);  // two exact discretisations of one system: rounding only
}

TEST(SimPhysics, SteadySineMatchesTheTransferFunction) {
  // A sine started at t = 0 with a 2 ms record: after the transient, the
  // amplitude and phase of v2 follow H(jω) (off resonance, decays are fast).
  const double fs = 1e7, f = 20e3, w = 2 * M_PI * f;
  acq::BenchCircuit c;
  c.damping = beta7();
  acq::DividerStateSpace ss(apc850_port(), c);
  drivers::sim::PiecewiseLinear pl;
  std::vector<double> t;
  const int n = 40000;
  for (int k = 0; k < n; ++k) {
    pl.t.push_back(k / fs);
    pl.v.push_back(std::sin(w * k / fs));
  }
  for (int k = n - 2000; k < n; ++k) t.push_back(k / fs);  // last 4 periods
  auto v2 = ss.simulate(pl, t);
  double re = 0, im = 0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    re += v2[k] * std::sin(w * t[k]);
    im += v2[k] * std::cos(w * t[k]);
  }
  cd got = cd(re, im) * (2.0 / t.size());
  cd want = ss.transfer(w);
  EXPECT_LT(std::abs(got - want) / std::abs(want), 2e-3);  // residual transient of the slowest modes
}

TEST(SimPhysics, DebyeNetworkFollowsTheConstantPhaseCapacitance) {
  const double c = 2e-9, tan_delta = 0.02;
  auto net = acq::debye_network_for_loss(c, tan_delta);
  ASSERT_FALSE(net.branches.empty());
  for (double f = 1e3; f <= 2e5; f *= 1.5) {
    const double w = 2 * M_PI * f;
    const cd got = net.capacitance(w), want = model::lossy_capacitance(c, tan_delta, w);
    EXPECT_LT(std::abs(got - want) / std::abs(want), 2e-4) << f;
    EXPECT_NEAR(-got.imag() / got.real(), tan_delta, 0.02 * tan_delta) << f;  // constant loss tangent
  }
  // Causality's price of a constant loss: the real part falls with frequency,
  // by (2δ/π)·ln(10) per decade (Kramers–Kronig), independent of the fit.
  const double r = model::lossy_capacitance(c, tan_delta, 2 * M_PI * 1e3).real() /
                   model::lossy_capacitance(c, tan_delta, 2 * M_PI * 1e4).real();
  EXPECT_NEAR(std::log(r), 2 * std::atan(tan_delta) / M_PI * std::log(10.0), 1e-12);
  EXPECT_NEAR(net.capacitance(2 * M_PI * 1e4).real() / net.capacitance(2 * M_PI * 1e5).real(), r, 1e-3);
}

// The diagnosis's frequency-domain twin of the bench (model/bench_response)
// against the bench's own state space: every circuit effect at once.
TEST(SimPhysics, BenchResponseModelEqualsTheSimulatedDivider) {
  model::EffectSet fx;
  fx.series_resistance_ohm = 12.0;
  fx.parallel_capacitance_f = 150e-12;
  fx.daq_input_resistance_ohm = 1e6;
  fx.r1_tolerance = 0.02;
  fx.mechanical_damping = 0.004;
  fx.dielectric_loss = 0.015;
  fx.dielectric_constant_phase = true;  // the law the bench realises (causal)
  const double r1 = 3140.0;
  acq::BenchCircuit c;
  c.damping = beta7();
  c.r1_ohm = r1 * (1 + fx.r1_tolerance);
  c.series_resistance_ohm = fx.series_resistance_ohm;
  c.parallel_capacitance_f = fx.parallel_capacitance_f;
  c.daq_input_resistance_ohm = fx.daq_input_resistance_ohm;
  c.dielectric_loss = fx.dielectric_loss;
  c.extra_damping_ratio = fx.mechanical_damping;
  acq::DividerStateSpace ss(apc850_port(), c);
  std::vector<double> f = {1e3, 20e3, 50.5e3, 51.5e3, 55e3, 80e3, 101e3, 120e3};
  auto z = model::bench_impedance(apc850_port(), beta7(), fx, r1, f);
  for (std::size_t i = 0; i < f.size(); ++i) {
    const cd h = ss.transfer(2 * M_PI * f[i]), want = r1 * h / (1.0 - h);
    EXPECT_LT(std::abs(z[i] - want) / std::abs(want), 5e-4) << f[i];  // the Debye fit's accuracy
  }
  // Without the loss the two are the same algebra.
  fx.dielectric_loss = c.dielectric_loss = 0;
  acq::DividerStateSpace exact(apc850_port(), c);
  z = model::bench_impedance(apc850_port(), beta7(), fx, r1, f);
  for (std::size_t i = 0; i < f.size(); ++i) {
    const cd h = exact.transfer(2 * M_PI * f[i]), want = r1 * h / (1.0 - h);
    EXPECT_LT(std::abs(z[i] - want) / std::abs(want), 1e-9) << f[i];
  }
  // DAQ effects: the reported ratio of a skewed, mis-gained channel 2.
  fx.channel_gain = 0.01;
  fx.channel_skew_s = 50e-9;
  for (double fi : f) {
    const double w = 2 * M_PI * fi;
    const cd h = exact.transfer(w) * 1.01 * std::exp(cd(0, -w * 50e-9));
    const cd want = r1 * h / (1.0 - h);
    const cd got = model::reported_impedance(model::tube_admittance(apc850_port(), beta7(), fx, w), fx, r1, w);
    EXPECT_LT(std::abs(got - want) / std::abs(want), 1e-9) << fi;
  }
}
