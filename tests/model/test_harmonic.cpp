// Harmonic admittance/impedance: modal superposition vs the direct complex solve,
// the low-frequency limit vs the analytic capacitance, and the extremes of |Z|
// vs the short-/open-circuit modal frequencies. Isotropic target material.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "model/harmonic.hpp"
#include "model/material_presets.hpp"
#include "model/modal.hpp"

using namespace piezo::model;

namespace {

PiezoMaterialE iso_target() {
  return to_e_form(to_d_form(IsotropicPiezoParams{6.66e10, 0.3333, -210e-12, 2294 * kEps0}));
}

class Harmonic : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    tm_ = new TubeModel(TubeGeometry{}, MeshOptions{});
    ModalSolver s(*tm_);
    ModalOptions o;
    o.n_modes = 20;  // first omitted coupled mode ~3× above the band (README)
    port_ = new ModalPortModel(s.port_model(iso_target(), o, &sc_));
    oc_ = s.solve(iso_target(), Electrodes::open_circuit, o);
  }
  static void TearDownTestSuite() {
    delete tm_;
    delete port_;
  }
  static TubeModel* tm_;
  static ModalPortModel* port_;
  static ModalResult sc_, oc_;
};
TubeModel* Harmonic::tm_ = nullptr;
ModalPortModel* Harmonic::port_ = nullptr;
ModalResult Harmonic::sc_, Harmonic::oc_;

// Golden-section search of an extremum of |Z(f)| (sign = +1: minimum, −1: maximum).
template <class F>
double extremum(F absz, double a, double b, double sign) {
  const double gr = 0.5 * (std::sqrt(5.0) - 1);
  double c = b - gr * (b - a), d = a + gr * (b - a);
  double fc = sign * absz(c), fd = sign * absz(d);
  while (b - a > 1e-7 * a) {
    if (fc < fd) {
      b = d, d = c, fd = fc, c = b - gr * (b - a), fc = sign * absz(c);
    } else {
      a = c, c = d, fc = fd, d = a + gr * (b - a), fd = sign * absz(d);
    }
  }
  return 0.5 * (a + b);
}

}  // namespace

TEST_F(Harmonic, ModalMatchesDirectAwayFromPeaks) {
  // Acceptance: |Z| within 0.1 % away from the peaks, seed ch. 5 damping β = 1e-7 s.
  // "Away": outside ±2 % of every active resonance / anti-resonance.
  RayleighDamping d;
  d.beta = 1e-7;
  std::vector<double> f = frequency_grid(1000, 120000, 1700);  // 71 points, direct is slow
  DirectHarmonicSolver ds(*tm_);
  auto ym = admittance_modal(*port_, f, d);
  auto yd = ds.admittance(iso_target(), f, d);
  std::vector<double> peaks = sc_.active_frequencies_hz();
  for (double x : oc_.active_frequencies_hz()) peaks.push_back(x);
  double worst = 0, worst_all = 0;
  int n_away = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    const double e = std::abs(std::abs(1.0 / ym[i]) / std::abs(1.0 / yd[i]) - 1);
    worst_all = std::max(worst_all, e);
    bool near = false;
    for (double p : peaks) near |= std::abs(f[i] / p - 1) < 0.02;
    if (near) continue;
    ++n_away;
    worst = std::max(worst, e);
    EXPECT_LT(e, 1e-3) << f[i] << " Hz";
  }
  EXPECT_GT(n_away, 50);
  std::printf("modal vs direct |Z|: max rel diff %.2e away from peaks (%d pts), %.2e overall\n",
              worst, n_away, worst_all);
}

TEST_F(Harmonic, LowFrequencyLimitIsTheTubeCapacitance) {
  // Acceptance: Z(ω→0) = 1/(jωC) with C = 2π εT33 L/ln(Do/Di) within 0.5 %.
  const double ca = tm_->analytic_capacitance(2294 * kEps0);
  std::vector<double> f = {1.0, 400.0};
  DirectHarmonicSolver ds(*tm_);
  auto ym = admittance_modal(*port_, f);
  auto yd = ds.admittance(iso_target(), f);
  for (std::size_t i = 0; i < f.size(); ++i) {
    const double w = 2 * M_PI * f[i];
    EXPECT_LT(std::abs(ym[i].imag() / (w * ca) - 1), 5e-3) << f[i];
    EXPECT_LT(std::abs(yd[i].imag() / (w * ca) - 1), 5e-3) << f[i];
    EXPECT_LT(std::abs(ym[i].real()), 1e-12 * std::abs(ym[i]));  // lossless
  }
  const double z400 = std::abs(1.0 / yd[1]);
  std::printf("|Z(400 Hz)| direct = %.1f Ω, modal = %.1f Ω (published 26804 Ω, %+.3f %%)\n", z400,
              std::abs(1.0 / ym[1]), 100 * (z400 / 26804 - 1));
  EXPECT_LT(std::abs(z400 / 26804 - 1), 5e-3);
  EXPECT_EQ(admittance_modal(*port_, std::vector<double>{0.0})[0], Complex(0.0));
}

TEST_F(Harmonic, ExtremaOfImpedanceAreTheModalFrequencies) {
  // Acceptance: |Z| minima at the short-circuit, maxima at the open-circuit active
  // modal frequencies within 0.1 %. Direct solve, light damping β = 1e-9 s
  // (ζ ≈ 3e-4 shifts the extrema by O(ζ²)), golden-section search within ±1.5 %.
  RayleighDamping d;
  d.beta = 1e-9;
  DirectHarmonicSolver ds(*tm_);
  auto absz = [&](double f) {
    return std::abs(1.0 / ds.admittance(iso_target(), std::vector<double>{f}, d)[0]);
  };
  for (double fr : sc_.active_frequencies_hz()) {
    if (fr > 150e3) continue;
    const double fmin = extremum(absz, fr * 0.985, fr * 1.015, +1);
    std::printf("|Z| minimum %.2f Hz vs short-circuit mode %.2f Hz (%+.4f %%)\n", fmin, fr,
                100 * (fmin / fr - 1));
    EXPECT_LT(std::abs(fmin / fr - 1), 1e-3);
  }
  for (double fa : oc_.active_frequencies_hz()) {
    if (fa > 150e3) continue;
    const double fmax = extremum(absz, fa * 0.985, fa * 1.015, -1);
    std::printf("|Z| maximum %.2f Hz vs open-circuit mode %.2f Hz (%+.4f %%)\n", fmax, fa,
                100 * (fmax / fa - 1));
    EXPECT_LT(std::abs(fmax / fa - 1), 1e-3);
  }
}

TEST_F(Harmonic, MaterialLossesArePassiveAndModalApproximationClose) {
  // Qm and tanδ (complex constants) in the direct solve: Re Y > 0 everywhere
  // (passive), and the first-order modal treatment agrees within 2 % away from peaks.
  MaterialLosses l;
  l.qm = 80;
  l.tan_delta = 0.014;
  std::vector<double> f = {5000, 30000, 70000, 115000};
  DirectHarmonicSolver ds(*tm_);
  auto yd = ds.admittance(iso_target(), f, {}, l);
  auto ym = admittance_modal(*port_, f, {}, l);
  for (std::size_t i = 0; i < f.size(); ++i) {
    EXPECT_GT(yd[i].real(), 0) << f[i];
    EXPECT_LT(std::abs(ym[i] / yd[i] - 1.0), 2e-2) << f[i];
  }
  // Pure dielectric loss at low frequency: Re Y / Im Y → tanδ·C0/C_static (only the
  // clamped part of the permittivity is lossy in this model).
  MaterialLosses dl;
  dl.tan_delta = 0.02;
  auto y = ds.admittance(iso_target(), std::vector<double>{100.0}, {}, dl)[0];
  EXPECT_NEAR(y.real() / y.imag(), 0.02 * port_->c_clamped / port_->c_static, 1e-4);
}

TEST(HarmonicGrid, FrequencyGridAndPreconditions) {
  auto f = frequency_grid(0, 120000, 200);
  ASSERT_EQ(f.size(), 601u);
  EXPECT_DOUBLE_EQ(f.back(), 120000);
  EXPECT_THROW(frequency_grid(10, 5, 1), std::invalid_argument);
  EXPECT_THROW(frequency_grid(0, 5, 0), std::invalid_argument);
  ModalPortModel p;
  p.c_clamped = 1e-9;
  p.c_static = 1e-9;
  EXPECT_THROW(admittance_modal(p, std::vector<double>{-1.0}), std::invalid_argument);
  auto z = impedance_from_admittance(std::vector<Complex>{Complex(0), Complex(0, 2)});
  EXPECT_TRUE(std::isinf(z[0].real()));
  EXPECT_DOUBLE_EQ(z[1].imag(), -0.5);
}
