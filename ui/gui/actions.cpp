// What the buttons do: start or replay a job, connect to the instruments,
// export. Each hands its work to the Job or TaskQueue thread and returns at
// once; outcomes come back into the AppState on the UI thread.
#include <cstdio>
#include "drivers/instrument_uri.hpp"
#include "jobs/bench_probe.hpp"
#include "jobs/export/report_export.hpp"
#include "jobs/nominal_material.hpp"
#include "jobs/measure/sim_bench.hpp"
#include "ui/gui/app_state.hpp"
#include "ui/gui/calibration_prompt.hpp"

namespace piezo::gui {

namespace {
// The simulated bench's spec with the panel's effects and disturbances; throws
// std::invalid_argument naming a bad item (jobs/measure/sim_bench.hpp).
acq::SimSpec sim_spec(const AppState& s) {
  jobs::SimBenchRequest r = s.instrument.sim;
  r.effects = jobs::split_sim_effects(s.instrument.sim_effects);  // "series_resistance=15, channel_skew=1e-7"
  r.disturbance = s.instrument.sim_disturbances;                  // "offset=0.005,hum=0.005"
  return jobs::sim_spec(r);
}
}  // namespace

void start_job(AppState& s, bool replay) {
  if (s.job.running()) return;
  jobs::PipelineRequest req = s.request;  // committed copy: edits during the run do not leak in
  req.instrument = s.instrument.awg;
  req.daq = s.instrument.daq;
  req.capture_out = s.capture_out;
  req.overwrite_capture = false;  // a technician's earlier capture is never overwritten silently
  const auto& presets = jobs::material_presets();
  req.material = presets.at(static_cast<std::size_t>(s.material_index) % presets.size()).name;
  req.plan.setup.material = req.material;
  if (s.transducer_id[0]) req.plan.setup.transducer_id = std::string(s.transducer_id);
  s.error.reset();
  s.warnings.clear();
  if (replay) {
    req.replay_capture = s.replay_path;
    if (req.replay_capture.empty()) {
      s.error = Problem{ErrorKind::Input, "open capture", "no capture file given",
                        "Type the path of a recorded capture (.h5) next to 'Replay capture'."};
      return;
    }
    req.heldout_capture = s.heldout_path;  // optional; read (contained) by the pipeline
  } else if (drivers::is_sim_address(req.instrument)) {
    try {
      req.sim = sim_spec(s);
    } catch (...) {
      s.error = problem_from_current_exception("simulated effects");
      return;
    }
  }
  if (!replay && req.heldout_plan) {  // the held-out drive on the plan as edited: its excitation only differs
    acq::MeasurementPlan ho = req.plan;
    ho.excitation = req.heldout_plan->excitation;
    req.heldout_plan = ho;
  }
  if (replay) req.heldout_plan.reset();
  if (!replay) attach_calibration(s.calibration, s.calibration_prompt, req);  // fixture standards first
  if (!s.job.start(req)) return;
  s.last_job_replay = replay;
  ++s.jobs_started;
  s.frame_ms_jobs.emplace_back();
  s.instrument.before_job = s.instrument.state;
  if (!replay) s.instrument.state = InstrumentForm::State::Measuring;
  s.log.push_back(replay ? "replay of " + req.replay_capture + " started"
                         : "measure and update started on " + req.instrument);
}

bool collect_job(AppState& s) {
  std::unique_ptr<jobs::PipelineResult> res;
  std::optional<Problem> problem;
  const bool cancelled = s.job.cancel_requested();
  if (!s.job.take(res, problem)) return false;
  s.result = std::move(res);
  s.verdict.reset();
  s.error = std::move(problem);
  s.warnings.clear();
  s.mag_view.fitted = s.phase_view.fitted = s.sv_view.fitted = s.residual_view.fitted = false;
  s.nyquist_view.fitted = false;
  s.nyquist.clear();
  s.nyquist_mode = 0;
  if (s.result && s.result->mode_figures && s.result->mode_figures->error.empty())
    for (const auto& c : s.result->curves)
      if (c.estimator == "prony")  // the estimate the figures were computed on
        s.nyquist = jobs::mode_nyquist(c.f_hz, c.z_ohm, s.result->mode_figures->figures);
  auto& in = s.instrument;
  if (s.error) {
    s.log.push_back("job failed at " + s.error->stage + ": " + s.error->message);
    if (s.error->kind == ErrorKind::Connection || s.error->kind == ErrorKind::Instrument) {
      in.state = InstrumentForm::State::Error;
      in.problem = s.error;
    } else if (in.state == InstrumentForm::State::Measuring) {
      in.state = in.before_job;
    }
    return true;
  }
  const auto& r = *s.result;
  s.log.push_back(cancelled ? "job cancelled" : "job finished");
  if (s.last_job_replay && r.capture_plan) {  // the Plan panel shows what was replayed, not the unused plan
    const double range = s.request.plan.range_v;
    s.request.plan = *r.capture_plan;
    s.request.plan.range_v = range;
    const std::string id = r.capture_plan->setup.transducer_id.value_or("");
    std::snprintf(s.transducer_id, sizeof s.transducer_id, "%s", id.c_str());
    s.log.push_back("  the Plan panel shows the replayed capture's set-up");
  }
  for (const auto& st : r.stages)
    s.log.push_back((st.ran ? "  ran " : "  skipped ") + st.name + ": " + st.note);
  for (const auto& w : r.warnings) s.log.push_back("  warning: " + w);
  if (!r.damping_from_resonances.empty())
    s.log.push_back("  damping from the resonances: " + r.damping_from_resonances);
  s.warnings = result_problems(r);
  judge_result(s);
  if (s.verdict)
    s.log.push_back("limits: " + s.verdict->status +
                    (s.verdict->reasons.empty() ? "" : " (" + std::to_string(s.verdict->reasons.size()) + " reason(s))"));
  if (r.awg_idn.empty()) {
    in.state = InstrumentForm::State::Replay;
  } else {
    in.state = InstrumentForm::State::Connected;
    in.idn_awg = r.awg_idn;
    in.idn_daq = r.daq_idn;
    in.problem.reset();
  }
  return true;
}

void judge_result(AppState& s) {
  s.verdict.reset();
  if (!s.limits || !s.result) return;
  s.verdict = jobs::report::evaluate_result(*s.limits, jobs::report_json(*s.result));
}

void load_limits(AppState& s) {
  const std::string path = s.limits_path;
  s.tasks.post("limits", [path]() -> TaskQueue::Apply {
    try {
      auto l = std::make_shared<const jobs::report::Limits>(jobs::report::read_limits(path));
      return [l](AppState& st) {
        st.limits = l;
        st.log.push_back("limits loaded: " + l->source + " (" + std::to_string(l->limits.size()) + " limit(s))");
        judge_result(st);
      };
    } catch (const jobs::report::LimitsError& e) {  // names the file and the line
      Problem pr{ErrorKind::Input, "limits", e.what(),
                 "Fix the limits file at the line named (README, 'Limits and the lot report'; "
                 "docs/limits-example.toml) and press 'Limits...' again."};
      return [pr](AppState& st) {
        st.limits.reset();
        st.verdict.reset();
        st.error = pr;
        st.log.push_back("limits not loaded: " + pr.message);
      };
    }
  });
}

void connect_instruments(AppState& s) {
  const std::string awg = s.instrument.awg, daq = s.instrument.daq;
  const double r1 = s.request.plan.setup.divider_r1_ohm;
  acq::SimSpec sim;
  try {
    if (drivers::is_sim_address(awg)) sim = sim_spec(s);
  } catch (...) {
    s.instrument.state = InstrumentForm::State::Error;
    s.instrument.problem = problem_from_current_exception("simulated effects");
    return;
  }
  s.instrument.state = InstrumentForm::State::Connecting;
  s.instrument.problem.reset();
  s.tasks.post("connect", [awg, daq, sim, r1]() -> TaskQueue::Apply {
    try {
      const jobs::BenchProbe p = jobs::probe_bench(awg, daq, sim, r1);
      return [p](AppState& st) {
        auto& in = st.instrument;
        in.state = InstrumentForm::State::Connected;
        in.idn_awg = p.awg_idn;
        in.idn_daq = p.daq_idn;
        in.description = p.description;
        st.log.push_back("connected: " + p.description);
      };
    } catch (...) {
      Problem pr = problem_from_current_exception("connect");
      return [pr](AppState& st) {
        auto& in = st.instrument;
        in.state = InstrumentForm::State::Error;
        in.idn_awg.clear();
        in.idn_daq.clear();
        in.problem = pr;
        st.log.push_back("connect failed: " + pr.message);
      };
    }
  });
}

void export_result(AppState& s, ExportFormat f) {
  if (!s.result) return;
  const std::string base = s.export_base;
  const char* ext = f == ExportFormat::Csv          ? ".csv"
                    : f == ExportFormat::Touchstone ? ".s1p"
                                                    : ".json";
  const std::string path = base + ext;
  std::shared_ptr<const jobs::PipelineResult> r = s.result;
  s.tasks.post("export " + path, [r, f, path]() -> TaskQueue::Apply {
    try {
      if (f == ExportFormat::Csv) jobs::export_csv(*r, path);
      if (f == ExportFormat::Touchstone) jobs::export_touchstone(*r, path);
      if (f == ExportFormat::Json) jobs::export_json(*r, path);
      return [path](AppState& st) { st.log.push_back("exported " + path); };
    } catch (...) {
      Problem pr = problem_from_current_exception("export");
      return [pr](AppState& st) {
        st.error = pr;
        st.log.push_back("export failed: " + pr.message);
      };
    }
  });
}

}  // namespace piezo::gui
