// FE tube model on the default mesh (MeshOptions{} = 2 × 24 Q2 elements):
// assembly of the split system, re-weight + modal solve of 10 modes (short and
// open circuit), a 600-point modal-superposition impedance sweep, and a
// divider transient (20000 samples at 10 MS/s). Targets (2-core machine):
// modal solve < 50 ms, sweep < 20 ms.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "model/harmonic.hpp"
#include "model/material_presets.hpp"
#include "model/modal.hpp"
#include "model/reduced_port.hpp"
#include "model/transient.hpp"

namespace {
using namespace piezo::model;

PiezoMaterialE material() {
  return to_e_form(to_d_form(IsotropicPiezoParams{6.66e10, 0.3333, -210e-12, 2294 * kEps0}));
}

void BM_AssembleTubeModel(benchmark::State& state) {
  for (auto _ : state) {
    TubeModel tm(TubeGeometry{}, MeshOptions{});
    benchmark::DoNotOptimize(tm.system().pattern().nonZeros());
  }
}
BENCHMARK(BM_AssembleTubeModel)->Unit(benchmark::kMillisecond);

void BM_ModalSolve10(benchmark::State& state) {
  TubeModel tm(TubeGeometry{}, MeshOptions{});
  ModalSolver s(tm);
  const auto m = material();
  const auto ec = state.range(0) ? Electrodes::open_circuit : Electrodes::short_circuit;
  ModalOptions o;
  o.n_modes = 10;
  for (auto _ : state) benchmark::DoNotOptimize(s.solve(m, ec, o).modes.size());
  state.SetLabel(state.range(0) ? "open circuit" : "short circuit");
}
BENCHMARK(BM_ModalSolve10)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Arg: end-face mass loading in percent of the tube mass (M + f·ΔM, ΔM built
// with the TubeModel): a port model with a mass fraction costs no re-assembly.
// Two materials in turn, as a fit asks: the solver keeps the last combined
// matrix and factor, which one material asked again would reuse.
void BM_PortModel20(benchmark::State& state) {
  TubeModel tm(TubeGeometry{}, MeshOptions{});
  ModalSolver s(tm);
  const PiezoMaterialE m[2] = {material(), to_e_form(to_d_form(IsotropicPiezoParams{
                                               6.66e10 * (1 + 1e-6), 0.3333, -210e-12, 2294 * kEps0}))};
  ModalOptions o;
  o.n_modes = 20;
  o.end_mass_fraction = 0.01 * static_cast<double>(state.range(0));
  int i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(s.port_model(m[i ^= 1], o).modes.size());
  state.SetLabel("end mass " + std::to_string(state.range(0)) + " %");
}
BENCHMARK(BM_PortModel20)->Arg(0)->Arg(2)->Unit(benchmark::kMillisecond);

// The reduced-basis port model (model/reduced_port.hpp) of the same tube:
// Arg 0 its basis (five snapshots' vectors — ModalSolver::port_vectors —
// and their projection, ReducedPortSpace made once), Arg 1 a port model from
// it 1 % off the centre, Arg 2 the same with its error estimates.
void BM_ReducedPort20(benchmark::State& state) {
  TubeModel tm(TubeGeometry{}, MeshOptions{});
  ModalSolver s(tm);
  const auto m = material();
  ModalOptions o;
  o.n_modes = 20;
  std::vector<ReducedPort::Point> points{{m, 0.0}};
  for (int c = 0; c < 4; ++c) {
    PiezoMaterialE p = m;
    double* v[4] = {&p.c_e11, &p.c_e12, &p.e31, &p.eps_s33};
    *v[c] *= 1.003;
    points.push_back({p, 0.0});
  }
  auto rp = ReducedPort::build(s, points, o);
  if (!rp) {
    state.SkipWithError("no reduced basis");
    return;
  }
  PiezoMaterialE near = m;
  near.c_e11 *= 1.01;
  near.eps_s33 *= 0.99;
  ReducedPort::Bound b;
  for (auto _ : state) {
    if (state.range(0) == 0) {
      std::vector<PortVectors> v;
      for (const auto& p : points) v.push_back(*s.port_vectors(p.material, o));
      benchmark::DoNotOptimize(ReducedPort::build(v, m, o, rp->space()).has_value());
    } else {
      benchmark::DoNotOptimize(rp->port_model(near, 0.0, state.range(0) == 2 ? &b : nullptr).modes.size());
    }
  }
  state.SetLabel(state.range(0) == 0 ? "basis (5 snapshots)" : state.range(0) == 1 ? "port model" : "port model + estimates");
}
BENCHMARK(BM_ReducedPort20)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

void BM_ImpedanceSweep600(benchmark::State& state) {
  TubeModel tm(TubeGeometry{}, MeshOptions{});
  ModalSolver s(tm);
  ModalOptions o;
  o.n_modes = 20;
  const auto port = s.port_model(material(), o);
  const auto f = frequency_grid(200, 120000, 200);  // 600 points
  RayleighDamping d;
  d.beta = 1e-7;
  for (auto _ : state) benchmark::DoNotOptimize(admittance_modal(port, f, d).data());
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(f.size()));
}
BENCHMARK(BM_ImpedanceSweep600)->Unit(benchmark::kMillisecond);

void BM_DividerTransient20k(benchmark::State& state) {
  TubeModel tm(TubeGeometry{}, MeshOptions{});
  ModalSolver s(tm);
  ModalOptions o;
  o.n_modes = 20;
  const auto port = s.port_model(material(), o);
  RayleighDamping d;
  d.beta = 1e-7;
  DividerSimulator sim(port, d, DividerCircuit{}, 1e7);
  std::vector<double> v1(20000);
  for (std::size_t k = 0; k < v1.size(); ++k) v1[k] = std::exp(-3000.0 * k / 1e7);
  for (auto _ : state) benchmark::DoNotOptimize(sim.simulate(v1).data());
}
BENCHMARK(BM_DividerTransient20k)->Unit(benchmark::kMillisecond);
}  // namespace
