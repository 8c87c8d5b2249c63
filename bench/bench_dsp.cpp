// Impedance estimators on divider-like signals (10 MS/s, three damped modes near
// 51/54/95 kHz, an RC step component, exp_decay drive, 1 % white noise):
//   Prony-SS on 1000 / 3000 / 20000 samples — decimated (band 120 kHz, the
//   default path of the CLI) and at the full rate, each with the full SVD and
//   the randomized SVD; the direct FFT ratio and the cross spectra on 1e6 samples.
// Target: the 3000-sample Prony estimate under 20 ms. BM_PronyFe repeats the
// Prony cases on the chapter-5 study's data: the FE tube's divider transient
// (APC850, β = 1e-7, 500 V exp_decay, 10 % noise per channel as the seed defines
// it; tests/dsp/fe_chapter5.hpp builds the same records).
// BM_ResidualInverse: the output-error residual's inverse DFT at the corpus's
// two shapes (a 20 000-sample capture and a 50 000-sample held-out chirp, both
// padded to 4n, decimation 33), the full real inverse against the decimated one
// (dsp/decimated_inverse, issue 43).
#include <benchmark/benchmark.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <vector>

#include "dsp/cross_spectra.hpp"
#include "dsp/decimated_inverse.hpp"
#include "dsp/fft.hpp"
#include "dsp/fft_ratio.hpp"
#include "dsp/prony_impedance.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/transient.hpp"
#include "model/tube_model.hpp"

namespace {
using namespace piezo;
constexpr double kFs = 1e7;

struct Signals {
  std::vector<double> v1, v2;
};

Signals make(std::size_t n, std::uint64_t seed) {
  Signals s;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> nd(0.0, 1.0);
  const double tw = 2.0 * std::numbers::pi;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = double(k) / kFs;
    const double v1 = std::exp(-3000.0 * t);
    const double v2 = v1 - 0.9 * std::exp(-85e3 * t) +
                      0.02 * std::exp(-1.6e3 * t) * std::sin(tw * 51.08e3 * t) +
                      0.008 * std::exp(-1.8e3 * t) * std::sin(tw * 53.96e3 * t + 0.4) +
                      0.03 * std::exp(-2.0e4 * t) * std::sin(tw * 94.6e3 * t + 1.0);
    s.v1.push_back(v1 + 0.01 * 0.3 * nd(rng));
    s.v2.push_back(v2 + 0.01 * 0.3 * nd(rng));
  }
  return s;
}

void BM_Prony(benchmark::State& st) {
  const auto n = static_cast<std::size_t>(st.range(0));
  const bool decimated = st.range(1) != 0;
  const auto svd = st.range(2) ? dsp::SvdMethod::Randomized : dsp::SvdMethod::Full;
  const Signals s = make(n, 1);
  dsp::PronyImpedanceOptions o;
  o.prony.svd = svd;
  if (decimated)
    o.prony.band_hz = 120e3;
  else
    o.prony.decimation = 1;
  const Eigen::VectorXd grid = dsp::make_grid(1e3, 120e3, 200);
  std::size_t order = 0;
  for (auto _ : st) {
    const auto r = dsp::impedance_prony({s.v1, s.v2, kFs, 3140.0, 0, {}}, grid, o);
    order = r.prony->order;
    benchmark::DoNotOptimize(r.z_ohm.data());
  }
  st.counters["order"] = double(order);
}
// args: samples, decimated (band 120 kHz → D = 16), randomized SVD
BENCHMARK(BM_Prony)
    ->Args({1000, 1, 0})
    ->Args({1000, 1, 1})
    ->Args({3000, 1, 0})
    ->Args({3000, 1, 1})
    ->Args({20000, 1, 0})
    ->Args({20000, 1, 1})
    ->Unit(benchmark::kMillisecond);
// Full rate: the balanced 3·ξ × η Hankel of N samples; the full SVD is O(N³)
// (3000: a 4500 × 1500 BDCSVD, seconds; 20000: 30000 × 10000, not attempted).
BENCHMARK(BM_Prony)
    ->Args({1000, 0, 0})
    ->Args({1000, 0, 1})
    ->Args({3000, 0, 1})
    ->Args({20000, 0, 1})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Prony)->Args({3000, 0, 0})->Iterations(1)->Unit(benchmark::kMillisecond);

// The chapter-5 records: 50000 samples from t = 0 of the FE divider transient,
// white noise of 0.1·std(clean channel) on each channel.
Signals make_fe(std::uint64_t seed) {
  const auto mat = model::resolve_material({"apc850", false, ""});
  model::TubeGeometry g;
  g.density_kg_m3 = mat.density_kg_m3;
  model::TubeModel tube(g);
  model::ModalSolver solver(tube);
  model::ModalOptions mo;
  mo.n_modes = 24;
  const auto port = solver.port_model(model::to_e_form(mat.d), mo);
  Signals s;
  for (std::size_t k = 0; k < 50000; ++k) s.v1.push_back(500.0 * std::exp(-1e-3 * double(k) / kFs));
  s.v2 = model::simulate_divider(port, {0.0, 1e-7}, model::DividerCircuit{}, s.v1, kFs);
  std::mt19937_64 rng(seed);
  for (auto* x : {&s.v1, &s.v2}) {
    double m = 0, v = 0;
    for (double a : *x) m += a / double(x->size());
    for (double a : *x) v += (a - m) * (a - m) / double(x->size());
    std::normal_distribution<double> nd(0.0, 0.1 * std::sqrt(v));
    for (double& a : *x) a += nd(rng);
  }
  return s;
}

void BM_PronyFe(benchmark::State& st) {
  static const Signals s = make_fe(1);
  const auto n = static_cast<std::size_t>(st.range(0));
  dsp::PronyImpedanceOptions o;
  o.prep.max_samples = n;
  o.prony.band_hz = 120e3;
  o.prony.svd = st.range(1) ? dsp::SvdMethod::Randomized : dsp::SvdMethod::Full;
  const Eigen::VectorXd grid = dsp::make_grid(1e3, 120e3, 200);
  std::size_t order = 0;
  for (auto _ : st) {
    const auto r = dsp::impedance_prony({s.v1, s.v2, kFs, 3140.0, 0, {}}, grid, o);
    order = r.prony->order;
    benchmark::DoNotOptimize(r.z_ohm.data());
  }
  st.counters["order"] = double(order);
}
// args: samples, randomized SVD (decimated path, band 120 kHz)
BENCHMARK(BM_PronyFe)
    ->Args({1000, 0})
    ->Args({3000, 0})
    ->Args({3000, 1})
    ->Args({20000, 0})
    ->Args({20000, 1})
    ->Unit(benchmark::kMillisecond);

void BM_FftRatio(benchmark::State& st) {
  const Signals s = make(static_cast<std::size_t>(st.range(0)), 2);
  dsp::FftRatioOptions o;
  o.fmax_hz = 120e3;
  for (auto _ : st) {
    const auto r = dsp::impedance_fft({s.v1, s.v2, kFs, 3140.0, 0, {}}, o);
    benchmark::DoNotOptimize(r.z_ohm.data());
  }
}
BENCHMARK(BM_FftRatio)->Arg(1000000)->Unit(benchmark::kMillisecond);

// Arg 0: the record's length n (nfft = 4n, decim 33, kmax = 1.25·nfft/33, as
// the fit's Problem); arg 1: 0 = RealFft::inverse of all nfft points, 1 =
// DecimatedInverse of the n/33 kept samples.
void BM_ResidualInverse(benchmark::State& st) {
  const std::size_t n = static_cast<std::size_t>(st.range(0)), nfft = 4 * n, decim = 33;
  const std::size_t kmax = nfft * 5 / (4 * decim), count = (n + decim - 1) / decim;
  std::mt19937 rng(1);
  std::normal_distribution<double> n01;
  std::vector<std::complex<double>> bins(nfft / 2 + 1, 0.0);
  for (std::size_t k = 0; k <= kmax; ++k) bins[k] = {n01(rng), n01(rng)};
  if (st.range(1) == 0) {
    dsp::RealFft fft(nfft);
    std::vector<double> out(n);
    for (auto _ : st) {
      fft.inverse(bins.data(), out.data(), n);
      benchmark::DoNotOptimize(out.data());
    }
  } else {
    dsp::DecimatedInverse dinv(nfft, kmax, decim, count);
    std::vector<double> out(count);
    for (auto _ : st) {
      dinv(bins.data(), out.data());
      benchmark::DoNotOptimize(out.data());
    }
  }
}
BENCHMARK(BM_ResidualInverse)
    ->Args({20000, 0})
    ->Args({20000, 1})
    ->Args({50000, 0})
    ->Args({50000, 1})
    ->Unit(benchmark::kMicrosecond);

// 1e6 samples as 20 records of 5e4 (the seed's cross-spectra set-up), and as
// one record in Welch segments of 5e4 with 50 % overlap.
void BM_CrossSpectra(benchmark::State& st) {
  const bool welch = st.range(0) != 0;
  std::vector<Signals> sig;
  std::vector<dsp::DividerRecord> recs;
  if (welch)
    sig.push_back(make(1000000, 3));
  else
    for (int k = 0; k < 20; ++k) sig.push_back(make(50000, 10 + k));
  for (const auto& s : sig) recs.push_back({s.v1, s.v2, kFs, 3140.0, 0, {}});
  dsp::CrossSpectraOptions o;
  o.segment = 50000;
  o.overlap = welch ? 0.5 : 0.0;
  o.window = {welch ? dsp::WindowKind::Hann : dsp::WindowKind::Rectangular, 0};
  o.fmax_hz = 120e3;
  for (auto _ : st) {
    const auto r = dsp::impedance_xspec(recs, o);
    benchmark::DoNotOptimize(r.z_ohm.data());
  }
}
BENCHMARK(BM_CrossSpectra)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
