#include "dsp/prony_ss.hpp"
#include "dsp/prony_impedance.hpp"
#include "dsp/features.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <chrono>

#include "bvd_model.hpp"

namespace {
using namespace piezo;
using cd = std::complex<double>;

TEST(PronySS, Scratch) {
  auto bvd_m = bvd::tube_bvd_rayleigh(1e-7);
  auto truth = dsp::find_features([&](double f){return bvd_m.impedance_at(f);}, 1e3, 120e3, 50, {});
  for (auto f: truth.resonances) std::printf("true res %.2f\n", f.f_hz);
  for (auto f: truth.antiresonances) std::printf("true anti %.2f\n", f.f_hz);
  std::printf("C true %.6g est %.6g\n", bvd_m.static_capacitance(), truth.capacitance_f);
  auto resp = bvd::divider_response(bvd_m, 3140, 500.0, 1e-3);
  const double fs = 1e7;
  const std::size_t n = 50000;
  auto v1c = bvd::sample(resp.v1, fs, n);
  auto v2c = bvd::sample(resp.v2, fs, n);
  std::printf("std v1 %g v2 %g\n", bvd::std_dev(v1c), bvd::std_dev(v2c));
  for (int seed = 1; seed <= 3; ++seed) {
  auto v1 = bvd::add_noise(v1c, 0.1, 100 + seed);
  auto v2 = bvd::add_noise(v2c, 0.1, 200 + seed);
  for (std::size_t ns : {1000u, 3000u}) for (int ord : {0, 8}) {
    dsp::DividerRecord rec{v1, v2, fs, 3140, 0, {}};
    dsp::PronyImpedanceOptions o;
    o.prep.max_samples = ns; if (ord) o.prony.order = ord; o.prony.noise_threshold = 2.0; o.prony.band_hz = 120e3;
    auto t0 = std::chrono::steady_clock::now();
    auto r = dsp::impedance_prony(rec, dsp::make_grid(1e3, 120e3, 200), o);
    auto t1 = std::chrono::steady_clock::now();
    std::printf("N=%zu order %zu  %.1f ms\n", ns, r.prony->order, std::chrono::duration<double, std::milli>(t1-t0).count());
    for (int k = 0; k < 0 && k < (int)r.prony->singular_values_normalized.size(); ++k) std::printf("%.2e ", r.prony->singular_values_normalized[k]);
    std::printf("\n");
    for (auto f: r.features.resonances) std::printf("  res %.2f (%.3f%%)\n", f.f_hz, 0.0);
    for (auto p: r.prony->poles) std::printf("  pole f %.1f xi %.4f\n", p.freq_hz, p.damping_ratio);
    for (auto f: r.features.antiresonances) std::printf("  anti %.2f\n", f.f_hz);
    double maxdb = 0;
    for (int k = 0; k < r.f_hz.size(); ++k) maxdb = std::max(maxdb, std::abs(20*std::log10(std::abs(r.z_ohm[k])/std::abs(bvd_m.impedance_at(r.f_hz[k])))));
    std::printf("  max dB err %.3f C %.6g\n", maxdb, r.features.capacitance_f);
  }
  }
}

}  // namespace
