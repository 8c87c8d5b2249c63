// The jobs' room (jobs/): the demo on the simulated bench (see demo_job.hpp).
#include "jobs/demo_job.hpp"

#include <filesystem>

#include "acquisition/calibration_plan.hpp"
#include "model/seed_circuit.hpp"

namespace piezo::jobs {

SimBenchRequest demo_sim_request(const DemoRequest& d) {
  SimBenchRequest r;
  r.material = "apc850";
  r.isotropic = true;
  r.set = "YE11=6.66e10,nu12=0.3333,d31=-210e-12,epsT33_rel=2294";
  r.noise = d.noise;
  r.seed = d.seed;
  r.effects = d.effects;
  r.disturbance = d.disturbances;  // also the held-out's bench
  return r;
}

PipelineRequest demo_bench_request(const DemoRequest& d) {
  const DemoRequest* a = &d;
  PipelineRequest req;
  req.instrument = "sim";
  req.plan.setup.divider_r1_ohm = model::kSeedR1Ohm;
  req.plan.setup.transducer_id = "demo-tube";
  req.plan.setup.material = "apc850";
  req.plan.samples = 20000;
  req.plan.pretrigger_samples = 200;
  req.plan.shots = a->shots;
  // The simulated "real" tube: the seed's Table 4/5 target material in the isotropic class.
  req.sim = sim_spec(demo_sim_request(d));
  req.diagnose = !a->no_diagnose;
  if (!a->no_calibrate && !a->calibrate.empty())
    req.calibration = acq::parse_calibration_list(a->calibrate, 1000.0);
  // Held-out data for the gap diagnosis: a chirp of the same tube, 1-150 kHz.
  acq::MeasurementPlan ho = req.plan;
  ho.excitation.kind = acq::Excitation::Chirp;
  ho.excitation.f_start_hz = 1e3;
  ho.excitation.f_stop_hz = 150e3;
  ho.excitation.burst_fraction = 0.6;
  req.heldout_plan = ho;
  req.material = "apc850";
  req.isotropic = true;
  req.compare_lm = true;  // the table shows oe, cmcm and lm
  return req;
}

PipelineRequest demo_pipeline_request(const DemoRequest& d) {
  namespace fs = std::filesystem;
  PipelineRequest req = demo_bench_request(d);
  req.capture_out = (fs::path(d.out_dir) / "demo-capture.h5").string();
  fs::create_directories(d.out_dir);  // last: bad input leaves nothing behind
  return req;
}

PipelineResult run_demo(const DemoRequest& d, const std::function<void(const PipelineProgress&)>& progress,
                        const std::atomic<bool>& cancel) {
  return run_pipeline(demo_pipeline_request(d), progress, cancel);
}

}  // namespace piezo::jobs
