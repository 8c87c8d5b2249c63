// The "Measure and update" pipeline (see pipeline.hpp).
#include "ui/pipeline.hpp"

#include <filesystem>

#include "acquisition/capture_file.hpp"
#include "acquisition/runner.hpp"
#include "dsp/cross_spectra.hpp"
#include "dsp/fft_ratio.hpp"
#include "dsp/prony_impedance.hpp"
#include "model/harmonic.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"

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

dsp::DividerRecord record_of(const acq::Capture& cap, const acq::Shot& s) {
  return {s.v1, s.v2, s.sample_rate_hz, cap.setup.divider_r1_ohm,
          static_cast<std::size_t>(std::max<std::int64_t>(0, s.pretrigger_samples)), s.daq_range_v};
}

Curve curve_of(const std::string& label, const dsp::ImpedanceResult& r) {
  Curve c;
  c.label = label;
  c.f_hz.assign(r.f_hz.data(), r.f_hz.data() + r.f_hz.size());
  c.z_ohm.assign(r.z_ohm.data(), r.z_ohm.data() + r.z_ohm.size());
  return c;
}

// Z(ω) of the capture: Prony-SS on the first transient "dut" shot (the
// estimate the update uses), with the direct FFT ratio and the averaged
// cross-spectra of all such shots as overlays.
dsp::ImpedanceResult estimate(const acq::Capture& cap, PipelineResult& out) {
  std::vector<const acq::Shot*> shots;
  for (const auto& s : cap.shots)
    if (s.role == acq::Role::Dut && s.excitation != acq::Excitation::Sine) shots.push_back(&s);
  if (shots.empty())
    throw std::invalid_argument("the capture holds no transient \"dut\" shot to estimate Z from");
  const acq::Shot& first = *shots.front();
  const double fmax = std::min(120e3, first.sample_rate_hz / 4), step = 100.0;
  dsp::PronyImpedanceOptions po;
  const std::size_t post = first.samples() - static_cast<std::size_t>(first.pretrigger_samples);
  po.prep.max_samples = std::min<std::size_t>(3000, post);
  po.prony.band_hz = fmax;
  po.features.fmin_hz = step;
  auto prony = dsp::impedance_prony(record_of(cap, first), dsp::make_grid(step, fmax, step), po);
  out.curves.push_back(curve_of("measured (Prony-SS)", prony));
  for (const auto& f : prony.features.resonances) out.resonances_hz.push_back(f.f_hz);
  for (const auto& f : prony.features.antiresonances) out.antiresonances_hz.push_back(f.f_hz);
  if (prony.prony) {
    out.singular_values = prony.prony->singular_values_normalized;
    out.order = static_cast<int>(prony.prony->order);
  }
  try {
    dsp::FftRatioOptions fo;
    fo.fmin_hz = step;
    fo.fmax_hz = fmax;
    out.curves.push_back(curve_of("measured (FFT)", dsp::impedance_fft(record_of(cap, first), fo)));
    std::vector<dsp::DividerRecord> recs;
    for (const auto* s : shots)
      if (s->excitation == first.excitation) recs.push_back(record_of(cap, *s));
    dsp::CrossSpectraOptions xo;
    xo.fmin_hz = step;
    xo.fmax_hz = fmax;
    out.curves.push_back(curve_of("measured (cross-spectra)", dsp::impedance_xspec(recs, xo)));
  } catch (const std::exception& e) {
    out.warnings.push_back(std::string("overlay estimators: ") + e.what());
  }
  return prony;
}

}  // namespace

PipelineResult run_pipeline(const PipelineRequest& req, const std::function<void(const PipelineProgress&)>& cb,
                            const std::atomic<bool>& cancel) {
  PipelineResult out;
  Stages progress{cb};
  acq::Capture cap = acquire(req, out, progress, cancel);
  if (cancel) return out;
  progress(0.45, "estimate: Prony-SS");
  auto z = estimate(cap, out);
  {
    char note[160];
    std::snprintf(note, sizeof note, "Prony-SS order %d on %zu samples: %zu resonances, %zu anti-resonances, C = %.4g F",
                  out.order, z.samples_used, out.resonances_hz.size(), out.antiresonances_hz.size(),
                  z.features.capacitance_f);
    out.stages.push_back({"estimate", true, note});
  }
  if (cancel) return out;
  out.stages.push_back({"update", false, "model updating not built into this version yet"});
  out.stages.push_back({"diagnose", false, "gap diagnosis not built into this version yet"});
  progress(1.0, "done");
  return out;
}

}  // namespace piezo::ui
