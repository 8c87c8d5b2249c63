// The pipeline's room (jobs/pipeline), acquire stage: acquire a capture on
// the bench (or read the one to replay), and the held-out capture of the same
// transducer with another plan.
#include <filesystem>

#include "acquisition/capture_file.hpp"
#include "acquisition/contained_read.hpp"
#include "acquisition/runner.hpp"
#include "drivers/instrument_uri.hpp"
#include "jobs/pipeline/stages.hpp"

namespace piezo::jobs::detail {

acq::Capture acquire(const PipelineRequest& req, PipelineResult& out, const Stages& progress,
                     const std::atomic<bool>& cancel, std::shared_ptr<drivers::sim::SimBench>& sim) {
  if (!req.replay_capture.empty()) {
    progress(0.05, "acquire: reading " + req.replay_capture);
    // A recorded capture is replayed with what it holds: a shot the reader refuses
    // (clipped beyond its range, NaN, a wrong shape) is left out and flagged.
    acq::ContainedReadOptions ro;
    ro.read.skip_invalid_shots = true;
    auto cap = req.replay_contained ? acq::read_capture_contained(req.replay_capture, ro)
                                    : acq::read_capture(req.replay_capture, ro.read);
    for (const auto& why : cap.rejected_shots) out.warnings.push_back("shot left out: " + why);
    out.capture_path = req.replay_capture;
    out.shots = static_cast<int>(cap.shots.size());
    out.stages.push_back({"acquire", false, "replay of " + req.replay_capture});
    return cap;
  }
  if (drivers::is_sim_address(req.instrument))
    sim = acq::make_sim_bench(req.sim, req.plan.setup.divider_r1_ohm);
  acq::Bench bench = acq::open_bench({req.instrument, req.daq.empty() ? std::nullopt : std::optional(req.daq)}, sim);
  out.awg_idn = bench.awg->identity();
  out.daq_idn = bench.daq->identity();
  acq::RunnerOptions ro;
  ro.overwrite = true;
  ro.software = "piezobench";
  if (!req.calibration.empty()) {  // the fixture standards first (issue 10)
    ro.calibration = req.calibration;
    ro.connect_standard = acq::make_standard_connector(bench, req.prompt);
  }
  std::string path = req.capture_out;
  if (!req.overwrite_capture) {  // the first free NAME-k.h5 (nothing recorded is lost)
    namespace fs = std::filesystem;
    const fs::path want(req.capture_out);
    std::error_code ec;
    for (int k = 2; fs::exists(fs::path(path), ec) && k < 100000; ++k)
      path = (want.parent_path() / (want.stem().string() + "-" + std::to_string(k) + want.extension().string())).string();
    if (path != req.capture_out)
      out.warnings.push_back(req.capture_out + " exists: this capture is written to " + path + " (nothing overwritten)");
  }
  auto res = acq::run_measurement(
      bench, req.plan, path, ro,
      [&](const acq::Progress& p) {
        progress(0.4 * p.shot / std::max(1, p.total), "acquire: shot " + std::to_string(p.shot + 1) + "/" +
                                                           std::to_string(p.total) + " " + p.stage);
      },
      &cancel);
  out.capture_path = res.capture.string();
  out.shots = res.shots_written;
  out.stages.push_back({"acquire", true, std::to_string(res.shots_written) + " shot(s) on " + bench.description});
  if (res.cancelled) out.warnings.push_back("cancelled during acquisition; kept " + std::to_string(res.shots_written) + " shot(s)");
  // Cancelled before the first shot: the capture holds nothing to read back
  // (the caller stops on `cancel` before using it).
  if (res.cancelled && res.shots_written == 0) return {};
  return acq::read_capture(res.capture);
}

// A second capture of the same transducer with another plan (e.g. a chirp),
// written as NAME-heldout.h5 next to the main capture, on the same bench.
acq::Capture acquire_heldout(const PipelineRequest& req, const acq::MeasurementPlan& plan,
                             std::shared_ptr<drivers::sim::SimBench>& sim, PipelineResult& out,
                             const std::atomic<bool>& cancel) {
  namespace fs = std::filesystem;
  fs::path main(out.capture_path.empty() ? req.capture_out : out.capture_path);  // where the main capture went
  const fs::path path = main.parent_path() / (main.stem().string() + "-heldout" + main.extension().string());
  acq::Bench bench = acq::open_bench({req.instrument, req.daq.empty() ? std::nullopt : std::optional(req.daq)}, sim);
  acq::RunnerOptions ro;
  ro.overwrite = true;
  ro.software = "piezobench";
  acq::MeasurementPlan linked = plan;  // the link back to the fit capture (/setup/heldout_of)
  linked.setup.heldout_of = main.filename().string();
  auto res = acq::run_measurement(bench, linked, path, ro, {}, &cancel);
  out.heldout_path = res.capture.string();
  out.stages.push_back({"acquire held-out", true, std::to_string(res.shots_written) + " shot(s) into " + out.heldout_path});
  return acq::read_capture(res.capture);
}

}  // namespace piezo::jobs::detail
