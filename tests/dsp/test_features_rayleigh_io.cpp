// Features on grids (quadratic refinement with propagated σ) and on the analytic
// model, Rayleigh damping (eqs 167-169), CSV/Touchstone formatting.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <sstream>

#include "bvd_model.hpp"
#include "dsp/features.hpp"
#include "dsp/impedance_io.hpp"
#include "dsp/rayleigh.hpp"

namespace {
using namespace piezo;
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

TEST(Features, GridRefinementAndCapacitance) {
  const auto m = bvd::tube_bvd_rayleigh(1e-7);
  const auto exact = dsp::find_features([&](double f) { return m.impedance_at(f); }, 500, 120e3, 5.0);
  ASSERT_EQ(exact.resonances.size(), 3u);
  ASSERT_EQ(exact.antiresonances.size(), 3u);
  const Eigen::VectorXd f = dsp::make_grid(200, 120e3, 200);
  Eigen::VectorXcd z(f.size());
  for (Eigen::Index k = 0; k < f.size(); ++k) z[k] = m.impedance_at(f[k]);
  const auto g = dsp::find_features(f, z, Eigen::VectorXd());
  ASSERT_EQ(g.resonances.size(), 3u);
  ASSERT_EQ(g.antiresonances.size(), 3u);
  // A parabola through ±2 bins of 200 Hz on peaks ~1.6 kHz wide: sub-bin, < 5e-4.
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR(g.resonances[k].f_hz / exact.resonances[k].f_hz, 1.0, 5e-4);
    EXPECT_NEAR(g.antiresonances[k].f_hz / exact.antiresonances[k].f_hz, 1.0, 5e-4);
  }
  EXPECT_NEAR(g.capacitance_f / m.static_capacitance(), 1.0, 1e-3);
  EXPECT_NEAR(exact.capacitance_f / m.static_capacitance(), 1.0, 1e-3);
}

// The propagated σ of a resonance and of the capacitance match their scatter.
TEST(Features, SigmaMatchesScatter) {
  const auto m = bvd::tube_bvd_rayleigh(1e-7);
  const Eigen::VectorXd f = dsp::make_grid(200, 120e3, 200);
  const double rel = 0.01;
  std::vector<double> fr, cap;
  double sig_f = 0, sig_c = 0;
  const int reps = 200;
  for (int s = 0; s < reps; ++s) {
    std::mt19937_64 rng(1000 + s);
    std::normal_distribution<double> nd(0.0, rel / std::sqrt(2.0));
    Eigen::VectorXcd z(f.size());
    Eigen::VectorXd zs(f.size());
    for (Eigen::Index k = 0; k < f.size(); ++k) {
      const cd zt = m.impedance_at(f[k]);
      z[k] = zt * (1.0 + cd(nd(rng), nd(rng)));
      zs[k] = rel * std::abs(zt);
    }
    const auto g = dsp::find_features(f, z, zs);
    ASSERT_GE(g.resonances.size(), 1u);
    fr.push_back(g.resonances[0].f_hz);
    sig_f += g.resonances[0].sigma_hz / reps;
    cap.push_back(g.capacitance_f);
    sig_c += g.capacitance_sigma_f / reps;
  }
  auto sd = [](const std::vector<double>& v) {
    double mu = 0, s = 0;
    for (double x : v) mu += x / double(v.size());
    for (double x : v) s += (x - mu) * (x - mu) / double(v.size() - 1);
    return std::sqrt(s);
  };
  EXPECT_NEAR(sig_f / sd(fr), 1.0, 0.25);
  EXPECT_NEAR(sig_c / sd(cap), 1.0, 0.25);
}

TEST(Rayleigh, TwoModesAndLeastSquares) {
  const dsp::RayleighDamping truth{12.0, 1e-7};
  const double w1 = kTwoPi * 50e3, w2 = kTwoPi * 95e3, w3 = kTwoPi * 53e3;
  const auto d = dsp::rayleigh_from_two_modes(w1, dsp::rayleigh_damping_ratio(truth, w1), w2,
                                              dsp::rayleigh_damping_ratio(truth, w2));
  EXPECT_NEAR(d.alpha / truth.alpha, 1.0, 1e-9);
  EXPECT_NEAR(d.beta / truth.beta, 1.0, 1e-9);
  std::vector<dsp::PoleInfo> modes;
  for (double w : {w1, w2, w3}) modes.push_back({{}, w / kTwoPi, dsp::rayleigh_damping_ratio(truth, w)});
  const auto l = dsp::rayleigh_fit(modes);
  EXPECT_NEAR(l.alpha / truth.alpha, 1.0, 1e-6);
  EXPECT_NEAR(l.beta / truth.beta, 1.0, 1e-9);
  EXPECT_THROW(dsp::rayleigh_from_two_modes(w1, 0.01, w1, 0.02), std::invalid_argument);
}

TEST(ImpedanceIo, CsvAndTouchstone) {
  dsp::ImpedanceResult r;
  r.method = "prony";
  r.f_hz.resize(2);  // (not = Vector2d(…): GCC 12 with AVX warns falsely, bug 106247)
  r.f_hz << 1000.0, 2000.0;
  r.z_ohm = Eigen::Vector2cd(cd(100.0, -5000.0), cd(50.0, -2500.0));
  std::ostringstream csv, s1p;
  dsp::write_impedance_csv(csv, r);
  EXPECT_EQ(csv.str(), "f_hz,re_ohm,im_ohm\n1000,100,-5000\n2000,50,-2500\n");
  dsp::write_touchstone_s1p(s1p, r, 50.0);
  const std::string t = s1p.str();
  EXPECT_NE(t.find("# HZ Z RI R 50\n"), std::string::npos);
  EXPECT_NE(t.find("\n1000 2 -100\n"), std::string::npos);  // normalised to 50 Ω
  EXPECT_NE(t.find("\n2000 1 -50\n"), std::string::npos);
}

}  // namespace
