// The effect table (model/effects.hpp): one entry per effect carries what
// the simulator, the model and both diagnosis paths read of it; the model's
// generic chain (model/bench_response.hpp) against the chain written out.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <set>
#include <string>

#include "model/bench_response.hpp"
#include "model/effects.hpp"

using namespace piezo::model;
using cd = std::complex<double>;

TEST(EffectTable, EveryEntryIsComplete) {
  std::set<std::string> names;
  const EffectSet neutral;
  for (const auto& e : effect_catalogue()) {
    SCOPED_TRACE(std::string(e.name));
    EXPECT_TRUE(names.insert(std::string(e.name)).second) << "duplicate name";
    EXPECT_FALSE(e.unit.empty());
    EXPECT_FALSE(e.meaning.empty());
    EXPECT_FALSE(e.separated_by.empty());
    EXPECT_LT(e.lower, e.upper);
    EXPECT_GE(e.typical, e.lower);
    EXPECT_LE(e.typical, e.upper);
    // A circuit or DAQ effect is applied by its term alone; a tube effect has code of its own.
    EXPECT_EQ(e.stage == EffectStage::tube, e.term == nullptr);
    // A conductance coordinate is a shunt resistance, absent at +inf.
    if (e.coordinate == EffectCoordinate::conductance) {
      EXPECT_EQ(e.stage, EffectStage::shunt);
      EXPECT_TRUE(std::isinf(neutral.*(e.field)));
    }
    // The simulator needs an element of its own except on channel 2.
    if (!e.simulated_natively) {
      EXPECT_EQ(e.stage, EffectStage::channel2);
    }
    // At its neutral value a term changes nothing.
    if (e.term) {
      const cd t = e.term(neutral.*(e.field), 2 * M_PI * 5e4);
      if (e.stage == EffectStage::series || e.stage == EffectStage::shunt) {
        EXPECT_EQ(std::abs(t), 0.0);
      } else {
        EXPECT_NEAR(std::abs(t - 1.0), 0.0, 1e-15);
      }
    }
  }
  EXPECT_EQ(names.size(), effect_catalogue().size());
}

TEST(EffectTable, CoordinatesRoundTrip) {
  const EffectSet neutral;
  for (const auto& e : effect_catalogue()) {
    SCOPED_TRACE(std::string(e.name));
    EXPECT_EQ(effect_coordinate(e, neutral.*(e.field)), 0.0);  // absent at x = 0
    const double x = effect_coordinate(e, e.typical);
    EXPECT_NEAR(x, 1.0, 1e-12);  // the typical size is one unit
    EXPECT_NEAR(effect_from_coordinate(e, x) / e.typical, 1.0, 1e-12);
    const auto [lo, hi] = effect_coordinate_bounds(e);
    EXPECT_LE(lo, 0.0);
    EXPECT_GT(hi, x);
    EffectSet s;
    add_effect_coordinate(e, s, x);
    EXPECT_NEAR(s.*(e.field) / e.typical, 1.0, 1e-12);
    EXPECT_TRUE(effect_value_physical(e, e.typical));
  }
  // σ of a conductance: σ_R = σ_G/G² (1 µS ± 0.1 µS is 1 MΩ ± 0.1 MΩ).
  const EffectInfo& daq = *find_effect("daq_input_resistance");
  EXPECT_NEAR(effect_sigma_from_coordinate(daq, 1.0, 0.1), 1e5, 1e-6);
  EXPECT_TRUE(std::isnan(effect_sigma_from_coordinate(daq, -1.0, 0.1)));
  EXPECT_FALSE(effect_value_physical(daq, std::numeric_limits<double>::infinity()));
}

TEST(EffectTable, GenericChainEqualsTheChainWrittenOut) {
  // bench_response.hpp's header, written out with the catalogue's values.
  EffectSet fx;
  fx.series_resistance_ohm = 12.5;
  fx.parallel_capacitance_f = 180e-12;
  fx.daq_input_resistance_ohm = 1.2e6;
  fx.r1_tolerance = -0.013;
  fx.channel_gain = 0.021;
  fx.channel_skew_s = 73e-9;
  const double r1 = 3140.0;
  for (double f : {1e3, 4.9e4, 5.3e4, 1.2e5}) {
    const double w = 2 * M_PI * f;
    const cd y_tube = cd(2e-5, w * 9e-9) + 1.0 / cd(800.0, 120.0);
    const cd za = 1.0 / y_tube + fx.series_resistance_ohm;
    const cd yn = 1.0 / za + cd(0, w * fx.parallel_capacitance_f) + 1.0 / fx.daq_input_resistance_ohm;
    const cd h = 1.0 / (1.0 + r1 * (1.0 + fx.r1_tolerance) * yn);
    const cd hp = h * (1.0 + fx.channel_gain) * std::exp(cd(0, -w * fx.channel_skew_s));
    const cd got = recorded_transfer(y_tube, fx, r1, w);
    EXPECT_LT(std::abs(got - hp) / std::abs(hp), 1e-13) << f;
    // And the neutral set leaves the divider alone.
    const cd bare = recorded_transfer(y_tube, EffectSet{}, r1, w);
    EXPECT_LT(std::abs(bare - 1.0 / (1.0 + r1 * y_tube)), 1e-15) << f;
  }
}

TEST(EffectTable, NamesListEveryEffect) {
  const std::string all = effect_names();
  for (const auto& e : effect_catalogue()) EXPECT_NE(all.find(std::string(e.name)), std::string::npos);
  const std::string wrapped = effect_names(4);
  EXPECT_NE(wrapped.find(",\n"), std::string::npos);
}

// tube_admittances (the fits' batched form) is tube_admittance at each ω, to
// the bit: the same operations per frequency, only the loops swapped.
TEST(BenchResponse, BatchedAdmittancesEqualThePointwiseOnes) {
  ModalPortModel port;
  port.c_clamped = 6.1e-9;
  port.c_residual = 2.3e-10;
  port.eps_t_over_s = 1.7;
  port.modes = {{2 * M_PI * 48e3, 2.1e-2, 9.0e10, true}, {2 * M_PI * 87e3, 7.5e-3, 3.1e11, true},
                {2 * M_PI * 131e3, 1.2e-3, 6.8e11, true}};
  const RayleighDamping d{15.0, 2.2e-9};
  std::vector<double> w;
  for (int k = 1; k <= 257; ++k) w.push_back(2 * M_PI * 800.0 * k);
  for (const double loss : {0.0, 3e-3}) {
    EffectSet fx;
    fx.mechanical_damping = 1.5e-3;
    fx.dielectric_loss = loss;
    std::vector<cd> y(w.size());
    tube_admittances(port, d, fx, w, 2e-9, y);
    for (std::size_t i = 0; i < w.size(); ++i) {
      const cd one = tube_admittance(port, d, fx, w[i], 2e-9);
      EXPECT_EQ(y[i].real(), one.real()) << i;
      EXPECT_EQ(y[i].imag(), one.imag()) << i;
    }
  }
}

// recorded_transfers (the effects present found once) is recorded_transfer at
// each ω, to the bit, with every stage's effects present and with none.
TEST(BenchResponse, BatchedTransfersEqualThePointwiseOnes) {
  EffectSet all;
  all.series_resistance_ohm = 3.5;
  all.parallel_capacitance_f = 4.7e-11;
  all.daq_input_resistance_ohm = 1e6;
  all.channel_skew_s = 2e-8;
  all.channel_gain = 4e-3;
  all.r1_tolerance = -2e-3;
  for (const EffectSet& fx : {EffectSet{}, all}) {
    std::vector<double> w;
    std::vector<cd> y;
    for (int k = 0; k <= 300; ++k) {
      w.push_back(2 * M_PI * 700.0 * k);
      y.emplace_back(1e-7 * k, 2e-4 * std::sin(0.05 * k) + 1e-6 * k);
    }
    std::vector<cd> t = y;
    recorded_transfers(t, fx, 1000.0, w);
    for (std::size_t i = 0; i < w.size(); ++i) {
      const cd one = recorded_transfer(y[i], fx, 1000.0, w[i]);
      EXPECT_EQ(t[i].real(), one.real()) << i;
      EXPECT_EQ(t[i].imag(), one.imag()) << i;
    }
  }
}
