// Capture file throughput: writing (with per-shot flush + fsync) and reading a
// seed-sized shot (20000 samples per channel, float64).
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>

#include "acquisition/capture_file.hpp"

namespace {
piezo::acq::Shot make_shot(std::size_t n) {
  piezo::acq::Shot s;
  s.sample_rate_hz = 1e7;
  s.excitation = piezo::acq::Excitation::ExpDecay;
  s.v1.resize(n);
  s.v2.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    s.v1[i] = std::exp(-3000.0 * i / 1e7);
    s.v2[i] = 0.5 * s.v1[i] * std::sin(2e-2 * i);
  }
  return s;
}

void BM_WriteCaptureShot(benchmark::State& state) {
  auto dir = std::filesystem::temp_directory_path() / "piezobench-bench";
  std::filesystem::create_directories(dir);
  piezo::acq::Setup setup;
  setup.divider_r1_ohm = 3140;
  auto shot = make_shot(static_cast<std::size_t>(state.range(0)));
  piezo::acq::WriterOptions opt;
  opt.overwrite = true;
  for (auto _ : state) {
    piezo::acq::CaptureWriter w(dir / "bench.h5", setup, opt);
    w.append(shot);
    w.close();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_WriteCaptureShot)->Arg(20000)->Unit(benchmark::kMillisecond);

void BM_ReadCapture(benchmark::State& state) {
  auto dir = std::filesystem::temp_directory_path() / "piezobench-bench";
  std::filesystem::create_directories(dir);
  piezo::acq::Capture cap;
  cap.setup.divider_r1_ohm = 3140;
  cap.shots.assign(4, make_shot(static_cast<std::size_t>(state.range(0))));
  piezo::acq::WriterOptions opt;
  opt.overwrite = true;
  piezo::acq::write_capture(dir / "bench-read.h5", cap, opt);
  for (auto _ : state) benchmark::DoNotOptimize(piezo::acq::read_capture(dir / "bench-read.h5"));
}
BENCHMARK(BM_ReadCapture)->Arg(20000)->Unit(benchmark::kMillisecond);
}  // namespace
