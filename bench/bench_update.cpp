// Model updating timings (acceptance: the whole update, all phases, default
// mesh, under 1 s): Table 4/5 features from the original model.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "model/material_presets.hpp"
#include "model/material_spec.hpp"
#include "model/transient.hpp"
#include "update/least_squares.hpp"
#include "update/output_error.hpp"
#include "update/port_fit.hpp"
#include "update/updater.hpp"

namespace {

namespace pu = piezo::update;
namespace pm = piezo::model;

const pu::TubeParams kOriginal{6.3e10, 0.31, -175e-12, 1576 * pm::kEps0};

pu::MeasuredFeatures table45() {
  pu::MeasuredFeatures f;
  f.resonances_hz = {51400, 55000, 82600};
  f.antiresonances_hz = {52400, 55800, 101600};
  f.low_z_ohm = 26804;
  f.low_z_hz = 400;
  return f;
}

// Everything the CLI does: assemble the tube, set up the solver, three phases.
void BM_UpdateCmcmFromScratch(benchmark::State& state) {
  const auto f = table45();
  for (auto _ : state) {
    pm::TubeModel tube(pm::TubeGeometry{});
    pm::ModalSolver solver(tube);
    auto r = pu::update_cmcm(tube, solver, pu::MaterialClass::isotropic(), kOriginal, f);
    if (!r.ok()) state.SkipWithError(r.message.c_str());
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_UpdateCmcmFromScratch)->Unit(benchmark::kMillisecond);

void BM_UpdateCmcm(benchmark::State& state) {
  const auto f = table45();
  pm::TubeModel tube(pm::TubeGeometry{});
  pm::ModalSolver solver(tube);
  const auto cls =
      state.range(0)
          ? pu::MaterialClass::transversely_isotropic(piezo::model::PiezoMaterialD{
                0, 0, -5.74e-12, 18.5e-12, 46e-12, 0, 400e-12, 590e-12, 1851 * pm::kEps0, 0})
          : pu::MaterialClass::isotropic();
  for (auto _ : state) {
    auto r = pu::update_cmcm(tube, solver, cls, kOriginal, f);
    if (!r.ok()) state.SkipWithError(r.message.c_str());
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_UpdateCmcm)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_UpdateLm(benchmark::State& state) {
  const auto f = table45();
  pm::TubeModel tube(pm::TubeGeometry{});
  pm::ModalSolver solver(tube);
  for (auto _ : state) {
    auto r = pu::update_lm(tube, solver, pu::MaterialClass::isotropic(), kOriginal, f);
    if (!r.ok()) state.SkipWithError(r.message.c_str());
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_UpdateLm)->Unit(benchmark::kMillisecond);

// Feature refinement of issue 6's chain: the output-error port fit of 6000
// samples (1 V exp_decay at 1e5 1/s, 10 MS/s, R1 = 3140 Ω) of the Table 4/5
// tube with 2e-4 V of white noise on v2 (16 averaged 3 % shots), from
// Prony-like features (+0.2 % / −0.1 % off).
void BM_PortFit(benchmark::State& state) {
  pm::TubeModel tube(pm::TubeGeometry{});
  pm::ModalSolver solver(tube);
  const auto m = pm::to_e_form(
      pm::to_d_form(pm::IsotropicPiezoParams{6.66e10, 0.3333, -210e-12, 2294 * pm::kEps0}));
  pm::ModalOptions o;
  o.n_modes = 24;
  const auto port = solver.port_model(m, o);
  const auto f = pu::model_frequencies(solver, m, 3, 3, pu::CmcmOptions{}.modal);
  std::vector<double> v1(6000);
  for (std::size_t k = 0; k < v1.size(); ++k) v1[k] = std::exp(-1e5 * static_cast<double>(k) / 1e7);
  auto v2 = pm::simulate_divider(port, {0.0, 1e-7}, {.r1_ohm = 3140.0}, v1, 1e7);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> nd(0.0, 2e-4);
  for (auto& x : v2) x += nd(rng);
  pu::PortFitStart st;
  for (int k = 0; k < 3; ++k) {
    st.resonances_hz.push_back(f.resonances_hz[k] * 1.002);
    st.antiresonances_hz.push_back(f.antiresonances_hz[k] * 0.999);
  }
  st.capacitance_f = port.c_static;
  for (auto _ : state) {
    auto r = pu::fit_port_model(v1, v2, 1e7, 3140.0, st);
    if (!r.converged) state.SkipWithError(r.message.c_str());
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_PortFit)->Unit(benchmark::kMillisecond);

// Issue 33's speed target: a one-shot output-error fit with the slow
// disturbances' model still under 0.5 s. One exp_decay shot (20 000 samples
// at 10 MS/s, 2 % white noise) of a tube 4 % off the nominal; Arg(1) adds DC
// offsets, 50 Hz hum with harmonics and 1/f noise at 1 % (the baseline is
// projected out, the 1/f noise whitened and the starts run again), Arg(0) is
// the same record without them (the white model, as before issue 33).
void BM_OutputErrorOneShot(benchmark::State& state) {
  pm::TubeModel tube(pm::TubeGeometry{});
  pm::ModalSolver solver(tube);
  const auto cls = pu::MaterialClass::isotropic();
  const auto nominal = pm::isotropic_params(pm::resolve_material({"apc850", true, ""}).d);
  auto truth = nominal;
  truth.y_e11 *= 1.04;
  truth.eps_t33 *= 0.98;
  const double fs = 10e6;
  const std::size_t n = 20000, pre = 200;
  std::vector<double> v1(n, 0.0);
  for (std::size_t i = pre; i < n; ++i) v1[i] = std::exp(-3000.0 * double(i - pre) / fs);
  pm::ModalOptions mo;
  mo.n_modes = 40;
  pm::DividerCircuit c;
  c.r1_ohm = 3140.0;
  std::vector<double> v2 = pm::simulate_divider(solver.port_model(cls.e_form(truth), mo), {0.0, 6e-8}, c, v1, fs);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> nd;
  auto rms = [](const std::vector<double>& v) {
    double a = 0;
    for (double x : v) a += x * x;
    return std::sqrt(a / double(v.size()));
  };
  for (auto* v : {&v1, &v2}) {
    const double s = 0.02 * rms(*v), level = 0.01 * rms(*v);
    double pink = 0;  // 1/f by a leaky integrator of white noise (enough for a timing)
    for (std::size_t i = 0; i < n; ++i) {
      (*v)[i] += s * nd(rng);
      if (state.range(0)) {
        pink = 0.999 * pink + 0.045 * level * nd(rng);
        const double th = 2 * M_PI * 50.0 * double(i) / fs + 0.7;
        (*v)[i] += 0.005 + 0.006 * (std::sin(th) + 0.3 * std::sin(2 * th)) + pink;
      }
    }
  }
  pu::OeData d;
  d.sample_rate_hz = fs;
  d.circuit.r1_ohm = 3140.0;
  d.shots.push_back({v1, v2, pre});
  bool modelled = false;
  for (auto _ : state) {
    const auto r = pu::fit_output_error(solver, cls, nominal, d);
    if (!r.ok()) state.SkipWithError(r.message.c_str());
    modelled = r.baseline.any();
    benchmark::DoNotOptimize(r);
  }
  state.counters["disturbances_modelled"] = modelled ? 1 : 0;
}
BENCHMARK(BM_OutputErrorOneShot)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(5);

}  // namespace
