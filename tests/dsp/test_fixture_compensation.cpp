// Fixture compensation: the correction formulas against error boxes built in
// closed form (a general bilinear box for open/short/load, the topologies the
// partial models assume for the others), the standards' polynomial fit, and
// the physical fixture fit against a transfer computed from known parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

#include "dsp/fixture_calibration.hpp"
#include "dsp/fixture_compensation.hpp"
#include "dsp/fixture_standards.hpp"

namespace {
using namespace piezo;
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kFmax = 120e3;

// A standard given exactly by real polynomial coefficients (Y for open and load, Z for short).
dsp::StandardModel poly(std::vector<double> c, bool admittance) {
  dsp::StandardModel m;
  m.admittance = admittance;
  m.fmax_hz = kFmax;
  m.omega_scale = kTwoPi * kFmax;
  m.c = Eigen::Map<Eigen::VectorXd>(c.data(), Eigen::Index(c.size()));
  m.cov = Eigen::MatrixXd::Zero(m.c.size(), m.c.size());
  return m;
}

// A DUT: a capacitor with one lossy resonance.
cd dut(double f) {
  const cd s(0, kTwoPi * f);
  const cd y =
      s * 2e-9 + s * 1e-9 / (s * s / std::pow(kTwoPi * 60e3, 2) + s * 0.02 / (kTwoPi * 60e3) + 1.0);
  return 1.0 / y;
}

TEST(FixtureCompensation, OpenShortLoadInvertsAnyBilinearErrorBox) {
  // Measured standards: open Y = G + jωC (+ a j(ω)^3 term), short Z = R + jωL, load Y ≈ 1/1000 +
  // jωC.
  const auto open = poly({2e-6, 5e-5, 1e-6, -3e-6}, true);
  const auto shrt = poly({11.0, 0.8}, false);
  const auto load = poly({9.7e-4, 4e-5, 2e-7}, true);
  const dsp::LoadStandard lv{1000.0, 47e-12};
  const dsp::FixtureCompensation comp(dsp::FixtureModel::OpenShortLoad, open, shrt, load, lv);
  for (double f : {500.0, 3e3, 20e3, 59e3, 60e3, 61e3, 119e3}) {
    // The unique bilinear map M with M(∞) = Z_o, M(0) = Z_s, M(Z_L) = Z_l, applied to the DUT.
    const cd zo = open.impedance(f), zs = shrt.impedance(f), zl = load.impedance(f),
             zL = lv.impedance(f);
    const cd c = (zl - zs) / (zL * (zo - zl)), a = zo * c;
    const cd zx = dut(f), zm = (a * zx + zs) / (c * zx + 1.0);
    EXPECT_LT(std::abs(comp.correct(f, zm) / zx - 1.0), 1e-10) << f;
  }
}

TEST(FixtureCompensation, PartialModelsAreExactForTheirTopologies) {
  const auto open = poly({1e-6, 9e-5}, true);  // shunt at the v2 node
  const auto shrt_series = poly({7.0, 0.3}, false);
  for (double f : {1e3, 30e3, 110e3}) {
    const cd yo = 1.0 / open.impedance(f), zx = dut(f);
    // open only: the shunt admittance across the DUT
    dsp::FixtureCompensation o(dsp::FixtureModel::Open, open, std::nullopt, std::nullopt);
    EXPECT_LT(std::abs(o.correct(f, 1.0 / (yo + 1.0 / zx)) / zx - 1.0), 1e-12);
    // short only: a series impedance
    dsp::FixtureCompensation s(dsp::FixtureModel::Short, std::nullopt, shrt_series, std::nullopt);
    EXPECT_LT(std::abs(s.correct(f, zx + shrt_series.impedance(f)) / zx - 1.0), 1e-12);
    // open-short: shunt at the v2 node, then the lead in series (the bench's fixture)
    const cd zlead(3.0, kTwoPi * f * 2e-7);
    const cd zsm = 1.0 / (yo + 1.0 / zlead);  // the short, measured through the shunt
    const cd zm = 1.0 / (yo + 1.0 / (zlead + zx));
    // a short model that is exactly Z_sm at this f: a constant (complex values need two
    // coefficients: R + jωL)
    const double w = kTwoPi * f / (kTwoPi * kFmax);
    const auto shrt_at_f = poly({zsm.real(), zsm.imag() / w}, false);
    dsp::FixtureCompensation os(dsp::FixtureModel::OpenShort, open, shrt_at_f, std::nullopt);
    EXPECT_LT(std::abs(os.correct(f, zm) / zx - 1.0), 1e-10) << f;
  }
}

TEST(FixtureCompensation, MissingStandardsAreNamed) {
  const auto open = poly({0.0, 1e-4}, true);
  try {
    dsp::FixtureCompensation c(dsp::FixtureModel::OpenShortLoad, open, std::nullopt, std::nullopt);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("short"), std::string::npos) << e.what();
  }
  EXPECT_THROW(dsp::FixtureCompensation(dsp::FixtureModel::Short, open, std::nullopt, std::nullopt),
               std::invalid_argument);
  EXPECT_EQ(dsp::FixtureCompensation::best_model(true, true, true),
            dsp::FixtureModel::OpenShortLoad);
  EXPECT_EQ(dsp::FixtureCompensation::best_model(true, false, true), dsp::FixtureModel::Open);
  EXPECT_EQ(dsp::FixtureCompensation::best_model(false, false, true), dsp::FixtureModel::None);
  for (auto m : {dsp::FixtureModel::None, dsp::FixtureModel::Open, dsp::FixtureModel::Short,
                 dsp::FixtureModel::OpenShort, dsp::FixtureModel::OpenShortLoad}) {
    EXPECT_EQ(dsp::parse_fixture_model(dsp::to_string(m)), m);
    EXPECT_FALSE(dsp::describe(m).empty());
  }
  EXPECT_FALSE(dsp::parse_fixture_model("magic"));
}

TEST(FixtureStandards, PolynomialFitRecoversTheStandardAndItsSpread) {
  dsp::MeasuredStandard m;
  const int n = 200;
  m.f_hz.resize(n);
  m.z_ohm.resize(n);
  m.z_sigma_ohm = Eigen::VectorXd::Constant(n, 1e-3);
  std::uint64_t state = 12345;
  auto gauss =
      [&] {  // Box–Muller on a small LCG: reproducible, no <random> distribution differences
        auto u = [&] {
          state = state * 6364136223846793005ULL + 1442695040888963407ULL;
          return (double((state >> 11) & ((1ULL << 53) - 1)) + 0.5) / double(1ULL << 53);
        };
        return std::sqrt(-2 * std::log(u())) * std::cos(kTwoPi * u());
      };
  for (int k = 0; k < n; ++k) {
    const double f = 600.0 * (k + 1);
    m.f_hz[k] = f;
    const cd z(10.0, kTwoPi * f * 1e-6);  // a short: R + jωL
    m.z_ohm[k] = z + cd(gauss(), gauss()) * (1e-3 / std::sqrt(2.0));
  }
  const auto s = dsp::fit_standard(m, false, 3, "short");
  EXPECT_NEAR(s.impedance(50e3).real(), 10.0, 5e-4);
  EXPECT_NEAR(s.impedance(50e3).imag(), kTwoPi * 50e3 * 1e-6, 5e-4);
  EXPECT_NEAR(s.chi2_reduced, 1.0, 0.2);     // the model fits to the noise
  EXPECT_LT(s.impedance_sigma(50e3), 2e-4);  // averaged over 200 points of σ 1e-3
  EXPECT_GT(s.impedance_sigma(50e3), 2e-5);
  EXPECT_THROW(s.impedance(130e3), std::invalid_argument);  // above the measured band
  EXPECT_NO_THROW(s.impedance(100.0));                      // below: extends to DC
  EXPECT_THROW(dsp::fit_standard(m, false, 9, "short"), std::invalid_argument);
  dsp::MeasuredStandard few = m;
  few.f_hz.conservativeResize(4);
  few.z_ohm.conservativeResize(4);
  few.z_sigma_ohm.conservativeResize(4);
  EXPECT_THROW(dsp::fit_standard(few, false, 3, "short"), std::invalid_argument);
  m.z_ohm[7] = cd(NAN, 0);
  EXPECT_THROW(dsp::fit_standard(m, false, 3, "short"), std::invalid_argument);
}

TEST(FixtureCalibration, PhysicalFitRecoversTheFixture) {
  // T_m = e^{−jωτ}/(u + jωβ + ρ·R1·Y_b): u = 1 (ideal DAQ), Cp = 120 pF, R1 off by +2 %, Rs = 7 Ω,
  // τ = 90 ns.
  const double r1 = 3140.0, rho = 1.02, cp = 120e-12, rs = 7.0, tau = 90e-9;
  const double beta = rho * r1 * cp;
  const dsp::LoadStandard lv{1000.0, 0.0};
  auto standard = [&](int which) {
    dsp::MeasuredStandard m;
    const int n = 150;
    m.f_hz.resize(n);
    m.z_ohm.resize(n);
    for (int k = 0; k < n; ++k) {
      const double f = 800.0 * (k + 1), w = kTwoPi * f;
      const cd yb = which == 0 ? cd(0) : which == 1 ? cd(1.0 / rs) : 1.0 / (rs + lv.impedance(f));
      const cd t = std::exp(cd(0, -w * tau)) / (1.0 + cd(0, w * beta) + rho * r1 * yb);
      m.f_hz[k] = f;
      m.z_ohm[k] = r1 * t / (1.0 - t);
    }
    return m;
  };
  dsp::CalibrationStandards cs;
  cs.r1_nominal_ohm = r1;
  cs.open = standard(0);
  cs.shrt = standard(1);
  cs.load = standard(2);
  cs.load_value = lv;
  const auto fx = dsp::fit_fixture(cs);
  EXPECT_TRUE(fx.converged);
  EXPECT_NEAR(*fx.fixture_capacitance_f / cp, 1.0, 1e-6);
  EXPECT_NEAR(*fx.lead_resistance_ohm / rs, 1.0, 1e-6);
  EXPECT_NEAR(*fx.r1_error, rho - 1.0, 1e-7);
  EXPECT_NEAR(*fx.skew_s, tau, 1e-13);
  EXPECT_NEAR(*fx.open_dc_transfer, 1.0, 1e-7);
  EXPECT_TRUE(fx.assumptions.empty());
  // Without the load, R1 cannot be told apart: held nominal, and said so.
  cs.load.reset();
  const auto no_load = dsp::fit_fixture(cs);
  EXPECT_FALSE(no_load.r1_error);
  EXPECT_FALSE(no_load.assumptions.empty());
  EXPECT_THROW(dsp::fit_fixture(dsp::CalibrationStandards{}), std::invalid_argument);
}

}  // namespace
