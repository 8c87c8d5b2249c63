// The pipeline's room (jobs/pipeline): the "Measure and update" job (see
// pipeline.hpp) — the stages in order (stages.hpp, one file each), the
// choice of the update, the model curves, progress and cancel.
#include "jobs/pipeline/pipeline.hpp"

#include <cstdio>

#include "acquisition/capture_file.hpp"
#include "acquisition/contained_read.hpp"
#include "jobs/pipeline/stages.hpp"

namespace piezo::jobs {

using namespace detail;

namespace {
PipelineResult run_stages(const PipelineRequest& req, const std::function<void(const PipelineProgress&)>& cb,
                          const std::atomic<bool>& cancel, WorkLog& log) {
  PipelineResult out;
  Stages progress{cb, &log};
  std::shared_ptr<drivers::sim::SimBench> sim;
  acq::Capture cap = acquire(req, out, progress, cancel, sim);
  if (cancel) return out;
  {  // the capture's own set-up (GUI: the Plan panel after a replay)
    acq::MeasurementPlan p;
    p.setup = cap.setup;
    p.shots = 0;
    for (const auto& s : cap.shots) {
      if (s.role != acq::Role::Dut) continue;
      if (p.shots++ == 0) {
        p.excitation.kind = s.excitation;
        if (s.amplitude_v) p.excitation.amplitude_v = *s.amplitude_v;
        if (s.decay_per_s) p.excitation.decay_per_s = *s.decay_per_s;
        if (s.frequency_hz) p.excitation.frequency_hz = *s.frequency_hz;
        if (s.f_start_hz) p.excitation.f_start_hz = *s.f_start_hz;
        if (s.f_stop_hz) p.excitation.f_stop_hz = *s.f_stop_hz;
        p.sample_rate_hz = s.sample_rate_hz;
        p.samples = s.v1.size();
        p.pretrigger_samples = static_cast<std::size_t>(std::max<std::int64_t>(0, s.pretrigger_samples));
      }
    }
    out.capture_plan = p;
  }
  if (req.use_calibration) calibrate_stage(cap, out);
  progress(0.45, "estimate: Prony-SS");
  // The estimate (Prony-SS features, FFT and cross-spectra overlays) feeds the
  // seed's chain and the plots; the output-error fit does not need it, so its
  // failure on a capture stops neither.
  std::optional<dsp::ImpedanceResult> z;
  try {
    z = estimate(cap, req.seed_chain, out);
    char note[160];
    std::snprintf(note, sizeof note, "Prony-SS order %d on %zu samples (%d shot(s) averaged): %zu resonances, %zu anti-resonances, C = %.4g F",
                  out.order, z->samples_used, out.shots_averaged, out.resonances_hz.size(), out.antiresonances_hz.size(),
                  z->features.capacitance_f);
    out.stages.push_back({"estimate", true, note});
    out.mode_figures = capture_mode_figures(cap, *z);
  } catch (const std::exception& e) {
    out.stages.push_back({"estimate", false, std::string("failed: ") + e.what()});
    out.warnings.push_back(std::string("the impedance estimate failed (") + e.what() +
                           "); the output-error fit runs on the samples alone");
  }
  if (cancel) return out;
  // One tube model for the seed's chain, the output-error fit, the model
  // curves and the diagnosis.
  const CaptureModel cm = capture_model(cap, req.material, req.isotropic);
  progress(0.55, "update: extended CMCM (the seed's chain)");
  SeedUpdate seed;
  if (!req.seed_chain) out.stages.push_back({"update (CMCM)", false, "not requested (the seed's chain is off)"});
  else if (z) seed = seed_update_stage(req, cap, cm, *z, out);
  else out.stages.push_back({"update (CMCM)", false, "needs the impedance estimate"});
  std::string seed_note = out.stages.back().note;
  if (cancel) return out;
  progress(0.62, "update: output-error fit");
  const auto oe = output_error_stage(req, cap, cm, out);
  const std::string oe_note = out.stages.back().note;
  if (cancel) return out;
  if (!req.seed_chain && req.seed_chain_fallback && z && !(oe && oe->ok())) {
    // The fallback: the seed's chain only where the output-error fit gave no update.
    progress(0.64, "update: extended CMCM (the seed's chain)");
    seed = seed_update_stage(req, cap, cm, *z, out);
    out.stages.back().note += " (run because the output-error fit did not converge)";
    seed_note = out.stages.back().note;
    if (cancel) return out;
  }
  // The per-mode figures on the estimator the capture supports best (issue
  // 34): the output-error fit's updated model, when it converged.
  if (oe && oe->ok()) {
    auto mm = model_mode_figures(cap, cm, *oe, out.mode_figures ? &*out.mode_figures : nullptr);
    if (mm.error.empty())
      out.mode_figures = std::move(mm);
    else
      out.warnings.push_back("per-mode figures of the updated model failed (" + mm.error +
                             "); the estimate's are reported");
  }

  // The pipeline's update: the output-error fit where it converged (its
  // constants carry sigma and status), else the seed's chain.
  UpdateOutcome u;
  // The seed's chain refused (issue 40): said, and the method that holds is used.
  if (!seed.refused.empty())
    out.warnings.push_back(std::string("the seed's chain is refused (") + seed.refused + "); " +
                           (oe && oe->ok() ? "the output-error fit's constants are used"
                                           : "and the output-error fit did not converge"));
  if (oe && oe->ok()) {
    u = {true, "output-error", oe->updated, oe->damping, 50e3};
    if (!out.resonances_hz.empty()) u.first_resonance_hz = out.resonances_hz.front();
    else u.first_resonance_hz = first_active_mode_hz(*cm.solver, cm.cls.e_form(oe->updated));
  } else if (seed.chosen.ok) {
    u = seed.chosen;
    model::ModalOptions mo;
    mo.n_modes = 16;
    const auto port = cm.solver->port_model(cm.cls.e_form(u.updated), mo);
    u.damping = damping_from_features(*z, out, &port);
    out.warnings.push_back(std::string("the output-error fit did not converge: the seed's chain (") +
                           (u.method == "cmcm" ? "extended CMCM" : "least squares on features") +
                           ") is used, with the sigmas its features give");
  }
  out.update_method = u.ok ? u.method : "";
  {
    std::string note;
    if (u.ok) {
      note = u.method == "output-error" ? "the output-error fit's constants and beta (with sigma)"
                                        : u.method == "cmcm" ? "the seed's extended CMCM (sigma from its features)"
                                                             : "least squares (LM) on the seed's features (sigma from them)";
      if (u.method == "output-error" && oe->lack_of_fit) note += "; the model class does not explain the capture";
    } else {
      note = "neither the output-error fit nor the seed's chain converged";
    }
    out.stages.push_back({"update", u.ok, note});
  }
  parameter_rows(cm.p0, u, seed, oe, sim.get(), out);
  if (!u.ok) {
    out.warnings.push_back("no model update: see the update stages");
    throw std::runtime_error("update: neither the output-error fit nor the seed's chain converged (" + oe_note +
                             "; " + seed_note + ")");
  }
  {  // Model curves on the measurement's grid (or a plain one): original and updated.
    std::vector<double> grid;
    if (!out.curves.empty()) grid = out.curves.front().f_hz;
    else
      for (double f = 100.0; f <= 120e3; f += 100.0) grid.push_back(f);
    out.curves.push_back({"original model", grid, model_z(*cm.solver, cm.cls.e_form(cm.p0), grid, u.damping)});
    out.curves.push_back({"updated model", grid, model_z(*cm.solver, cm.cls.e_form(u.updated), grid, u.damping)});
  }
  if (!req.diagnose) {
    out.stages.push_back({"diagnose", false, "not requested"});
  } else {
    std::optional<acq::Capture> heldout;
    if (!req.heldout_capture.empty()) {
      out.heldout_path = req.heldout_capture;
      try {
        heldout = req.replay_contained ? acq::read_capture_contained(req.heldout_capture)
                                       : acq::read_capture(req.heldout_capture);
      } catch (const std::exception& e) {
        if (!req.heldout_optional) throw;
        out.warnings.push_back("the held-out capture " + req.heldout_capture + " cannot be read (" + e.what() +
                               "): diagnosed without it");
        out.heldout_path.clear();
      }
    } else if (req.heldout_plan && req.replay_capture.empty()) {
      progress(0.65, "acquire: held-out capture");
      heldout = acquire_heldout(req, *req.heldout_plan, sim, out, cancel);
    }
    if (cancel) return out;
    progress(0.7, "diagnose: gap");
    try {
      diagnose_stage(req, cap, cm, heldout ? &*heldout : nullptr, u, out, progress, cancel);
    } catch (const std::exception& e) {
      // The capture and the update stand; the diagnosis failing must not lose them.
      out.stages.push_back({"diagnose", false, std::string("failed: ") + e.what()});
      out.warnings.push_back(std::string("gap diagnosis failed: ") + e.what() +
                             " - the update above is still valid; try more shots or a held-out capture");
    }
  }
  progress(1.0, "done");
  return out;
}
}  // namespace

PipelineResult run_pipeline(const PipelineRequest& req, const std::function<void(const PipelineProgress&)>& cb,
                            const std::atomic<bool>& cancel) {
  WorkLog log;
  log.open("acquire");
  PipelineResult out = run_stages(req, cb, cancel, log);
  log.close();
  for (const auto& p : log.phases())
    if (p.phase != "done") out.work.push_back(p);
  return out;
}

}  // namespace piezo::jobs
