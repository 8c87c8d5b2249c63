#pragma once
// A capture of the embedded simulated bench, written to `path` and read back
// (the same files the CLI writes), for tests that need real shots.
#include <filesystem>
#include <string>

#include "acquisition/bench.hpp"
#include "acquisition/capture_file.hpp"
#include "acquisition/plan.hpp"
#include "acquisition/runner.hpp"
#include "acquisition/sim_setup.hpp"

namespace piezo::test {

// A scratch folder under the build tree (PIEZO_BINARY_DIR/tests-tmp/NAME),
// created if needed: captures the tests write and read back.
inline std::filesystem::path scratch_dir(const std::string& name) {
  const std::filesystem::path d = std::filesystem::path(PIEZO_BINARY_DIR) / "tests-tmp" / name;
  std::filesystem::create_directories(d);
  return d;
}

inline acq::MeasurementPlan seed_lab_plan(int shots) {
  acq::MeasurementPlan p;  // the seed's lab test: R1 = 3140 Ω, 1 V exp_decay at 3000 1/s, 10 MS/s
  p.setup.divider_r1_ohm = 3140.0;
  p.setup.material = "apc850";
  p.samples = 20000;
  p.pretrigger_samples = 200;
  p.shots = shots;
  return p;
}

inline acq::MeasurementPlan chirp_plan(int shots) {
  auto p = seed_lab_plan(shots);
  p.excitation.kind = acq::Excitation::Chirp;
  p.excitation.f_start_hz = 1e3;
  p.excitation.f_stop_hz = 150e3;
  p.excitation.burst_fraction = 0.6;  // rings down inside the record
  return p;
}

inline acq::Capture sim_capture(const std::shared_ptr<drivers::sim::SimBench>& sim, const acq::MeasurementPlan& plan,
                                const std::filesystem::path& path) {
  acq::Bench bench = acq::open_bench({"sim", std::nullopt}, sim);
  acq::RunnerOptions ro;
  ro.overwrite = true;
  auto res = acq::run_measurement(bench, plan, path, ro);
  return acq::read_capture(res.capture);
}

}  // namespace piezo::test
