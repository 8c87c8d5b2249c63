#pragma once
// The jobs' room (jobs/): `piezobench demo` — the main job end to end on the
// embedded simulated bench: the seed's lab measurement (R1 = 3140 Ω, 1 V
// exp_decay at 3000 1/s, 20000 samples at 10 MS/s) of a simulated tube with
// the seed's Table 4/5 target material, the fixture standards, a held-out
// chirp, then every stage of the pipeline (jobs/pipeline/pipeline.hpp, the
// same as the GUI's "Measure and update"). ui/cli/cmd_demo.cpp prints it.
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "jobs/measure/sim_bench.hpp"
#include "jobs/pipeline/pipeline.hpp"

namespace piezo::jobs {

struct DemoRequest {
  std::string out_dir = "demo-out";
  double noise = 0.005;
  std::uint64_t seed = 2016;
  std::vector<std::string> effects;  // NAME=VALUE, bench effects the simulated bench adds
  // A real bench's slow disturbances, the option string of
  // drivers::sim::parse_disturbances ("offset=V,hum=V,..."; "" = none).
  std::string disturbances;
  bool no_diagnose = false;
  std::string calibrate = "open,short,load";
  bool no_calibrate = false;
  int shots = 16;
};

// The demo's simulated tube (the seed's Table 4/5 target material in the
// isotropic class) with the request's noise, seed, effects and disturbances:
// the simulated bench's request (jobs/measure/sim_bench.hpp) the GUI starts from.
SimBenchRequest demo_sim_request(const DemoRequest& req);

// The demo's bench and plan without its files: the simulated tube, the
// record, the fixture standards, the held-out chirp, the nominal material.
// The GUI opens on it (its defaults are the CLI's, issue 41 item 5). Throws
// std::invalid_argument for a bad effect, disturbance string or calibration list.
PipelineRequest demo_bench_request(const DemoRequest& req);

// The pipeline's request of the demo (creates `out_dir`). Throws
// std::invalid_argument for a bad effect, disturbance string or calibration list.
PipelineRequest demo_pipeline_request(const DemoRequest& req);

PipelineResult run_demo(const DemoRequest& req, const std::function<void(const PipelineProgress&)>& progress,
                        const std::atomic<bool>& cancel);

}  // namespace piezo::jobs
