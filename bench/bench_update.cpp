// Model updating timings (acceptance: the whole update, all phases, default
// mesh, under 1 s): Table 4/5 features from the original model.
#include <benchmark/benchmark.h>

#include "update/least_squares.hpp"
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

}  // namespace
