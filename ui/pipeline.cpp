// The "Measure and update" pipeline (see pipeline.hpp).
#include "ui/pipeline.hpp"

#include <filesystem>

#include "acquisition/capture_file.hpp"
#include "acquisition/runner.hpp"

namespace piezo::ui {

namespace {

struct Stages {
  const std::function<void(const PipelineProgress&)>& cb;
  void operator()(double f, const std::string& s) const {
    if (cb) cb(PipelineProgress{f, s});
  }
};

acq::Capture acquire(const PipelineRequest& req, PipelineResult& out, const Stages& progress,
                     const std::atomic<bool>& cancel) {
  if (!req.replay_capture.empty()) {
    progress(0.05, "reading " + req.replay_capture);
    auto cap = acq::read_capture(req.replay_capture);
    out.capture_path = req.replay_capture;
    out.shots = static_cast<int>(cap.shots.size());
    out.stages.push_back({"acquire", false, "replay of " + req.replay_capture});
    return cap;
  }
  std::shared_ptr<drivers::sim::SimBench> sim;
  if (req.instrument == "sim") sim = acq::make_sim_bench(req.sim, req.plan.setup.divider_r1_ohm);
  acq::Bench bench = acq::open_bench({req.instrument, req.daq.empty() ? std::nullopt : std::optional(req.daq)}, sim);
  acq::RunnerOptions ro;
  ro.overwrite = true;
  ro.software = "piezobench";
  auto res = acq::run_measurement(
      bench, req.plan, req.capture_out, ro,
      [&](const acq::Progress& p) {
        progress(0.4 * p.shot / std::max(1, p.total), "acquire: shot " + std::to_string(p.shot + 1) + "/" +
                                                           std::to_string(p.total) + " " + p.stage);
      },
      &cancel);
  out.capture_path = res.capture.string();
  out.shots = res.shots_written;
  out.stages.push_back({"acquire", true, std::to_string(res.shots_written) + " shot(s) on " + bench.description});
  if (res.cancelled) out.warnings.push_back("cancelled during acquisition; kept " + std::to_string(res.shots_written) + " shot(s)");
  return acq::read_capture(res.capture);
}

}  // namespace

PipelineResult run_pipeline(const PipelineRequest& req, const std::function<void(const PipelineProgress&)>& cb,
                            const std::atomic<bool>& cancel) {
  PipelineResult out;
  Stages progress{cb};
  acq::Capture cap = acquire(req, out, progress, cancel);
  if (cancel) return out;
  progress(0.45, "estimate");
  out.stages.push_back({"estimate", false, "impedance estimators not built into this version yet"});
  out.stages.push_back({"update", false, "model updating not built into this version yet"});
  out.stages.push_back({"diagnose", false, "gap diagnosis not built into this version yet"});
  progress(1.0, "done");
  return out;
}

}  // namespace piezo::ui
