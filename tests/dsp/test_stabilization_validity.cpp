// Prony stabilization chart and per-shot validity flags on the analytic BVD
// divider (lab drive, 10 MS/s): the circuit's poles come out stable from the
// order that resolves them on; a shot of another transducer is flagged for
// coherence and reconstruction, a clipped one for clipping.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "bvd_model.hpp"
#include "dsp/stabilization.hpp"
#include "dsp/validity.hpp"

namespace {
using namespace piezo;

struct Shots {
  std::vector<std::vector<double>> v1, v2;
  std::vector<dsp::DividerRecord> records() const {
    std::vector<dsp::DividerRecord> r;
    for (std::size_t k = 0; k < v1.size(); ++k)
      r.push_back({v1[k], v2[k], 1e7, 3140.0, 200, std::nullopt});
    return r;
  }
};

Shots shots_of(const bvd::Bvd& m, int n, double noise, std::uint64_t seed) {
  const auto resp = bvd::divider_response(m, 3140.0, 1.0, 3000.0);
  Shots s;
  for (int k = 0; k < n; ++k) {
    s.v1.push_back(bvd::add_noise(bvd::sample(resp.v1, 1e7, 8200, 200), noise, seed + 2 * k));
    s.v2.push_back(bvd::add_noise(bvd::sample(resp.v2, 1e7, 8200, 200), noise, seed + 2 * k + 1));
  }
  return s;
}

dsp::PronyImpedanceOptions prony() {
  dsp::PronyImpedanceOptions o;
  o.prep.max_samples = 3000;
  o.prony.band_hz = 120e3;
  return o;
}

TEST(Stabilization, CircuitPolesAreStableAcrossOrders) {
  const auto m = bvd::tube_bvd_q(150);
  const auto s = shots_of(m, 1, 1e-4, 3);
  const auto recs = s.records();
  dsp::StabilizationOptions so;
  so.min_order = 4;
  so.max_order = 16;
  so.fmax_hz = 120e3;
  const auto chart = dsp::stabilization_chart(recs[0], prony(), so);
  EXPECT_EQ(chart.orders.size(), 7u);
  EXPECT_GE(chart.selected_order, 8u);
  const auto resp = bvd::divider_response(m, 3140.0, 1.0, 3000.0);
  // Every oscillating circuit pole is found, and marked stable, at the orders >= 10.
  for (const auto& p : resp.circuit_poles) {
    const double f = p.imag() / (2 * M_PI);
    if (f < 1e3) continue;  // the drive's and the divider's real poles
    for (std::size_t order = 10; order <= 16; order += 2) {
      const auto it = std::find_if(chart.poles.begin(), chart.poles.end(),
                                   [&](const dsp::StabilizationPole& q) {
                                     return q.order == order && std::abs(q.freq_hz - f) < 0.002 * f;
                                   });
      ASSERT_NE(it, chart.poles.end()) << f << " Hz at order " << order;
      EXPECT_EQ(it->stability, dsp::PoleStability::Stable) << f << " Hz at order " << order;
    }
  }
  dsp::StabilizationOptions bad;
  bad.min_order = 10;
  bad.max_order = 4;
  EXPECT_THROW(dsp::stabilization_chart(recs[0], prony(), bad), std::invalid_argument);
}

TEST(ShotValidity, AStrangerAndAClippedShotAreFlagged) {
  auto s = shots_of(bvd::tube_bvd_q(150), 5, 2e-3, 11);
  // Shot 3 comes from another transducer (its modes 3 % higher), shot 4 is clipped.
  const auto other = shots_of(bvd::make_bvd({51.8e3, 55.0e3, 81.8e3}, {52.6e3, 55.6e3, 98.0e3},
                                            2.5e-9, {0.005, 0.005, 0.005}),
                              1, 2e-3, 99);
  s.v2[3] = other.v2[0];
  for (auto& x : s.v1[4]) x = std::min(x, 0.8);
  dsp::ShotValidityOptions vo;
  vo.fmin_hz = 1e3;
  vo.fmax_hz = 120e3;
  const auto rep = dsp::check_shots(s.records(), prony(), vo);
  ASSERT_EQ(rep.shots.size(), 5u);
  for (int k : {0, 1, 2}) {
    EXPECT_TRUE(rep.shots[k].flags.empty())
        << k << ": " << (rep.shots[k].flags.empty() ? "" : rep.shots[k].flags[0]);
    EXPECT_GT(rep.shots[k].coherence, 0.99);
    EXPECT_LT(rep.shots[k].reconstruction_ratio, 1.5);
  }
  auto has = [&](int k, const char* flag) {
    return std::find(rep.shots[k].flags.begin(), rep.shots[k].flags.end(), flag) !=
           rep.shots[k].flags.end();
  };
  EXPECT_TRUE(has(3, "low coherence")) << rep.shots[3].coherence;
  EXPECT_TRUE(has(4, "clipped"));
  EXPECT_EQ(rep.coherence.size(), rep.f_hz.size());
  EXPECT_THROW(dsp::check_shots({}, prony()), std::invalid_argument);
}

}  // namespace
