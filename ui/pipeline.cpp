// The "Measure and update" pipeline (see pipeline.hpp).
#include "ui/pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>

#include "acquisition/capture_calibration.hpp"
#include "acquisition/capture_file.hpp"
#include "acquisition/contained_read.hpp"
#include "acquisition/divider_record.hpp"
#include "acquisition/runner.hpp"
#include "drivers/instrument_uri.hpp"
#include "dsp/cross_spectra.hpp"
#include "dsp/fft.hpp"
#include "dsp/fft_ratio.hpp"
#include "dsp/prony_impedance.hpp"
#include "dsp/prony_ss.hpp"
#include "dsp/shot_ensemble.hpp"
#include "model/bench_response.hpp"
#include "model/effects.hpp"
#include "model/harmonic.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"
#include "ui/capture_fit.hpp"
#include "update/gap_output_error.hpp"
#include "update/least_squares.hpp"
#include "update/port_fit.hpp"
#include "update/rayleigh.hpp"
#include "update/updater.hpp"

namespace piezo::ui {

namespace {

struct Stages {
  const std::function<void(const PipelineProgress&)>& cb;
  void operator()(double f, const std::string& s) const {
    if (cb) cb(PipelineProgress{f, s});
  }
};

acq::Capture acquire(const PipelineRequest& req, PipelineResult& out, const Stages& progress,
                     const std::atomic<bool>& cancel, std::shared_ptr<drivers::sim::SimBench>& sim) {
  if (!req.replay_capture.empty()) {
    progress(0.05, "reading " + req.replay_capture);
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
  fs::path main(req.capture_out);
  const fs::path path = main.parent_path() / (main.stem().string() + "-heldout" + main.extension().string());
  acq::Bench bench = acq::open_bench({req.instrument, req.daq.empty() ? std::nullopt : std::optional(req.daq)}, sim);
  acq::RunnerOptions ro;
  ro.overwrite = true;
  ro.software = "piezobench";
  auto res = acq::run_measurement(bench, plan, path, ro, {}, &cancel);
  out.heldout_path = res.capture.string();
  out.stages.push_back({"acquire held-out", true, std::to_string(res.shots_written) + " shot(s) into " + out.heldout_path});
  return acq::read_capture(res.capture);
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
// The fixture from the capture's calibration shots, when it has any. A
// failure is a warning: the transducer's shots are still estimated, uncorrected.
void calibrate_stage(const acq::Capture& cap, PipelineResult& out) {
  const bool any = std::any_of(cap.shots.begin(), cap.shots.end(), [](const acq::Shot& s) { return s.role != acq::Role::Dut; });
  if (!any) return;
  try {
    acq::CaptureCalibrationOptions co;
    co.fmax_hz = std::min(120e3, cap.shots.front().sample_rate_hz / 4);
    auto c = acq::calibrate_from_capture(cap, co);
    if (!c) return;
    out.fixture = c->fixture;
    out.fixture_model = c->model_description;
    const auto& f = c->fixture;
    char note[300];
    std::snprintf(note, sizeof note, "fixture from %s: Cp %.1f pF, lead R %.2f ohm, R1 error %+.3f %%, skew %.1f ns",
                  c->model_description.c_str(), f.fixture_capacitance_f.value_or(0) * 1e12,
                  f.lead_resistance_ohm.value_or(0), f.r1_error.value_or(0) * 100, f.skew_s.value_or(0) * 1e9);
    out.stages.push_back({"calibrate", true, note});
    for (const auto& n : c->notes) out.warnings.push_back("fixture calibration: " + n);
  } catch (const std::exception& e) {
    out.stages.push_back({"calibrate", false, std::string("failed: ") + e.what()});
    out.warnings.push_back(std::string("fixture calibration failed (") + e.what() +
                           "); the transducer's shots are used without fixture correction");
  }
}

dsp::ImpedanceResult estimate(const acq::Capture& cap, bool refine_features, PipelineResult& out) {
  const std::optional<dsp::FixtureCalibration>& fx = out.fixture;
  bool fixture_in_fit = false;  // the port fit ran with the measured fixture in its circuit
  std::vector<const acq::Shot*> shots;
  for (const auto& s : cap.shots)
    if (s.role == acq::Role::Dut && s.excitation != acq::Excitation::Sine) shots.push_back(&s);
  if (shots.empty())
    throw std::invalid_argument("the capture holds no transient \"dut\" shot to estimate Z from");
  const acq::Shot& first = *shots.front();
  const double fmax = std::min(120e3, first.sample_rate_hz / 4), step = 100.0;
  // Repeated shots of one drive are averaged sample by sample before the fit
  // (white noise drops by √N; the transient is identical from shot to shot).
  std::vector<double> v1(first.v1), v2(first.v2);
  int averaged = 1;
  for (std::size_t k = 1; k < shots.size(); ++k) {
    const auto& s = *shots[k];
    if (s.samples() != first.samples() || s.sample_rate_hz != first.sample_rate_hz ||
        s.pretrigger_samples != first.pretrigger_samples || s.excitation != first.excitation ||
        s.amplitude_v != first.amplitude_v || s.decay_per_s != first.decay_per_s)
      continue;
    for (std::size_t i = 0; i < v1.size(); ++i) {
      v1[i] += s.v1[i];
      v2[i] += s.v2[i];
    }
    ++averaged;
  }
  for (std::size_t i = 0; i < v1.size(); ++i) {
    v1[i] /= averaged;
    v2[i] /= averaged;
  }
  out.shots_averaged = averaged;
  dsp::DividerRecord avg{v1, v2, first.sample_rate_hz, cap.setup.divider_r1_ohm,
                         static_cast<std::size_t>(std::max<std::int64_t>(0, first.pretrigger_samples)),
                         first.range_v(1), first.range_v(2)};
  dsp::PronyImpedanceOptions po;
  po.ramp_onset = true;  // the AWG ramps from idle at -dt onto its first sample
  // The samples before the first decimated one enter Z as recorded: the tube's
  // modes above the band, which the noise-set order leaves out (see
  // acq::bench_prony_options).
  po.direct_samples = dsp::PronyImpedanceOptions::kDirectFilterLength;
  const std::size_t post = first.samples() - static_cast<std::size_t>(first.pretrigger_samples);
  po.prep.max_samples = std::min<std::size_t>(6000, post);
  po.prony.band_hz = fmax;
  po.features.fmin_hz = step;
  auto prony = dsp::impedance_prony(avg, dsp::make_grid(step, fmax, step), po);
  // The first three resonance / anti-resonance pairs and the capacitance are
  // refined by the output-error fit of the modal port model to the same
  // samples (update/port_fit.hpp): Prony's zeros of Z(s) carry a truncation
  // bias where the noise sets its order (+0.2 … 0.3 % on the third resonance,
  // +1 % on nu12 after the update). Prony's values stay when the fit fails.
  if (refine_features) {
    auto& fr = prony.features.resonances;
    auto& fa = prony.features.antiresonances;
    const std::size_t n = std::min<std::size_t>({3, fr.size(), fa.size()});
    const std::size_t pre = avg.pretrigger_samples, nfit = std::min(post, po.prep.max_samples);
    try {
      if (n == 0 || !(prony.features.capacitance_f > 0))
        throw std::invalid_argument("no features to start from");
      update::PortFitStart st;
      for (std::size_t k = 0; k < n; ++k) {
        st.resonances_hz.push_back(fr[k].f_hz);
        st.antiresonances_hz.push_back(fa[k].f_hz);
        st.damping_ratios.push_back(fr[k].damping_ratio);
      }
      st.capacitance_f = prony.features.capacitance_f;
      double m1 = 0, m2 = 0;  // DAQ offsets, as dsp's front end removes them
      for (std::size_t i = 0; pre >= 16 && i < pre; ++i) {
        m1 += v1[i] / static_cast<double>(pre);
        m2 += v2[i] / static_cast<double>(pre);
      }
      // Start one sample before t = 0 (the idle level) when there is a
      // pretrigger: the fit takes its input as at rest before the first sample
      // and linear between samples, which is then the AWG's ramp onto the
      // burst (drivers/sim/sim_bench.cpp) rather than a jump half a sample off.
      const std::size_t lead = pre > 0 ? 1 : 0;
      // A measured fixture (calibration shots) goes into the circuit the port
      // is simulated in: true R1, Cp at node 2, lead R; channel 2's delay τ is
      // moved to the input (the response at t_k − τ to v1 is the response at
      // t_k to v1 delayed by τ: v1 interpolated at k − τ·fs, idle before).
      update::PortFitOptions pfo;
      double r1_fit = cap.setup.divider_r1_ohm;
      double d = 0.0;
      if (fx) {
        r1_fit *= 1.0 + fx->r1_error.value_or(0.0);
        pfo.fixture_capacitance_f = std::max(0.0, fx->fixture_capacitance_f.value_or(0.0));
        pfo.lead_resistance_ohm = std::max(0.0, fx->lead_resistance_ohm.value_or(0.0));
        d = fx->skew_s.value_or(0.0) * first.sample_rate_hz;
      }
      auto v1_at = [&](double q) {  // v1 − offset at fractional record index q
        if (q <= 0) return v1[0] - m1;
        const auto k = static_cast<std::size_t>(std::floor(q));
        if (k + 1 >= v1.size()) return v1.back() - m1;
        const double w = q - double(k);
        return (1 - w) * v1[k] + w * v1[k + 1] - m1;
      };
      std::vector<double> a(nfit), b(nfit);
      for (std::size_t i = 0; i < nfit; ++i) {
        a[i] = v1_at(double(pre - lead + i) - d);
        b[i] = v2[pre - lead + i] - m2;
      }
      const auto fit = update::fit_port_model(a, b, first.sample_rate_hz, r1_fit, st, pfo);
      if (!fit.converged) throw std::runtime_error(fit.message);
      for (std::size_t k = 0; k < n; ++k) {
        fr[k].f_hz = fit.features.resonances_hz[k];
        fa[k].f_hz = fit.features.antiresonances_hz[k];
        if (k < fit.features.resonance_sigma_hz.size()) {
          fr[k].sigma_hz = fit.features.resonance_sigma_hz[k];
          fa[k].sigma_hz = fit.features.antiresonance_sigma_hz[k];
        }
      }
      prony.features.capacitance_f = fit.features.low_frequency_capacitance();
      fixture_in_fit = fx.has_value();
    } catch (const std::exception& e) {
      out.warnings.push_back(
          std::string("port-model refinement of the features skipped (Prony's kept): ") + e.what());
    }
  }
  // Without the port fit, Prony's capacitance holds the fixture's: Z_m = Z_v2/(1 + r1_error)
  // with the fixture capacitance Cp across the v2 node, so C_m = (C + Cp)·(1 + r1_error).
  if (fx && !fixture_in_fit && (fx->fixture_capacitance_f || fx->r1_error)) {
    const double c_m = prony.features.capacitance_f;
    const double c = c_m / (1.0 + fx->r1_error.value_or(0.0)) - fx->fixture_capacitance_f.value_or(0.0);
    if (c > 0) {
      prony.features.capacitance_f = c;
      char note[200];
      std::snprintf(note, sizeof note,
                    "capacitance corrected for the measured fixture: %.5g F measured -> %.5g F of the transducer", c_m, c);
      out.warnings.push_back(note);
    } else {
      out.warnings.push_back("the measured fixture capacitance exceeds the measured capacitance: not corrected");
    }
  }
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
    out.curves.push_back(curve_of("measured (FFT)", dsp::impedance_fft(acq::divider_record(cap, first), fo)));
    std::vector<dsp::DividerRecord> recs;
    for (const auto* s : shots)
      if (s->excitation == first.excitation) recs.push_back(acq::divider_record(cap, *s));
    dsp::CrossSpectraOptions xo;
    xo.fmin_hz = step;
    xo.fmax_hz = fmax;
    out.curves.push_back(curve_of("measured (cross-spectra)", dsp::impedance_xspec(recs, xo)));
  } catch (const std::exception& e) {
    out.warnings.push_back(std::string("overlay estimators: ") + e.what());
  }
  return prony;
}

// κ/ω² of the port model's symmetric mode nearest f (1 without a model): the
// modal damping is α + βκ, not α + βω² (update/rayleigh.hpp).
double kappa_ratio_near(const model::ModalPortModel* port, double f_hz) {
  if (!port) return 1.0;
  const model::PortMode* best = nullptr;
  for (const auto& m : port->modes)
    if (m.symmetric && !m.residual &&
        (!best || std::abs(m.omega - 2 * M_PI * f_hz) < std::abs(best->omega - 2 * M_PI * f_hz)))
      best = &m;
  return best && best->omega > 0 ? best->kappa / (best->omega * best->omega) : 1.0;
}

// Rayleigh damping of the model curves from the damping ratios of the zeros of
// Z(s) at the first two resonances (the short-circuit modes; eqs 168-169 with
// the model's κ/ω² of those modes). Where the two-parameter fit is not
// physical (α < 0 in every normal run), the one-parameter damping the two
// modes support with its sigma, and their measured Qm (update::damping_from_modes,
// issue 19); the seed's β = 1e-7 s only when the resonances give no damping.
model::RayleighDamping damping_from_features(const dsp::ImpedanceResult& z, PipelineResult& out,
                                             const model::ModalPortModel* port) {
  model::RayleighDamping d{0.0, 1e-7};
  const auto& r = z.features.resonances;
  if (r.size() < 2 || !std::isfinite(r[0].damping_ratio) || !std::isfinite(r[1].damping_ratio)) return d;
  const auto fit = update::damping_from_modes(r[0].f_hz, r[0].damping_ratio, r[1].f_hz,
                                              r[1].damping_ratio, kappa_ratio_near(port, r[0].f_hz),
                                              kappa_ratio_near(port, r[1].f_hz));
  if (!fit.ok) {
    out.warnings.push_back("damping from the resonances unusable (" + fit.message +
                           "); model curves use beta = 1e-7 s");
    return d;
  }
  char buf[320];
  if (fit.model == "rayleigh (alpha, beta)")
    std::snprintf(buf, sizeof buf, "%s: alpha %.4g 1/s, beta %.4g s", fit.model.c_str(),
                  fit.damping.alpha, fit.damping.beta);
  else if (fit.damping.alpha == 0)
    std::snprintf(buf, sizeof buf, "%s: beta %.4g +- %.2g s", fit.model.c_str(), fit.damping.beta,
                  fit.beta_sigma);
  else
    std::snprintf(buf, sizeof buf, "%s: alpha %.4g +- %.2g 1/s", fit.model.c_str(),
                  fit.damping.alpha, fit.alpha_sigma);
  char qm[160];
  std::snprintf(qm, sizeof qm, "; measured Qm %.4g at %.4g kHz, %.4g at %.4g kHz", fit.qm1,
                r[0].f_hz / 1e3, fit.qm2, r[1].f_hz / 1e3);
  out.damping_from_resonances =
      std::string(buf) + qm + (fit.note.empty() ? "" : " (" + fit.note + ")");
  return fit.damping;
}

std::vector<std::complex<double>> model_z(model::ModalSolver& solver, const model::PiezoMaterialE& m,
                                          const std::vector<double>& f, const model::RayleighDamping& d) {
  model::ModalOptions mo;
  mo.n_modes = 20;
  auto port = solver.port_model(m, mo);
  auto y = model::admittance_modal(port, f, d);
  return model::impedance_from_admittance(y);
}

struct UpdateOutcome {
  bool ok = false;
  std::string method;  // "output-error" | "cmcm" | "lm"
  update::TubeParams updated;
  model::RayleighDamping damping;
  double first_resonance_hz = 50e3;
};

// The seed's chain (chapter 6-7): extended CMCM on the estimate's features,
// least squares (LM) on the same features where CMCM does not converge (or
// beside it, `req.compare_lm`). Never throws: its failure is a stage note.
struct SeedUpdate {
  UpdateOutcome chosen;                     // CMCM's, else LM's
  std::optional<update::TubeParams> cmcm, lm;
};

SeedUpdate seed_update_stage(const PipelineRequest& req, const CaptureModel& cm, const dsp::ImpedanceResult& z,
                             PipelineResult& out) {
  SeedUpdate s;
  try {
    update::MeasuredFeatures feat;
    feat.resonances_hz = out.resonances_hz;
    feat.antiresonances_hz = out.antiresonances_hz;
    if (feat.resonances_hz.size() > 3) feat.resonances_hz.resize(3);
    if (feat.antiresonances_hz.size() > 3) feat.antiresonances_hz.resize(3);
    if (!(z.features.capacitance_f > 0))
      throw std::runtime_error("the estimate has no low-frequency capacitance");
    feat.low_z_hz = 400.0;  // the seed's low-frequency point (Table 4/5)
    feat.low_z_ohm = 1.0 / (2 * M_PI * feat.low_z_hz * z.features.capacitance_f);
    feat.validate();

    update::UpdateOptions uo;
    // Measured features are not exactly reachable by the model (noise, three
    // resonances for two stiffnesses), so the outer sweeps settle to a
    // least-squares point more slowly than on exact data: allow more sweeps and
    // stop at 1e-6 relative change (far below the features' uncertainty).
    uo.max_sweeps = 40;
    uo.sweep_tolerance = 1e-6;
    const auto r = update::update_cmcm(*cm.tube, *cm.solver, cm.cls, cm.p0, feat, uo);
    std::string note;
    {
      char buf[200];
      std::snprintf(buf, sizeof buf, "extended CMCM %s: %d elastic + %d piezo iterations in %d sweeps",
                    r.ok() ? "converged" : "did NOT converge", r.iterations_elastic, r.iterations_piezo,
                    r.sweeps);
      note = buf;
      if (!r.ok()) note += ": " + r.message;
    }
    if (r.ok()) {
      s.cmcm = r.updated;
      s.chosen = {true, "cmcm", r.updated, {}, 50e3};
    }
    if (!r.ok() || req.compare_lm) {
      // Second, independent updater on the same features (update/least_squares.hpp):
      // no mode-shape pairing, so a start far from the answer (mode veering, an
      // ambiguous MAC) does not stop it.
      try {
        const auto lm = update::update_lm(*cm.tube, *cm.solver, cm.cls, cm.p0, feat);
        char buf[200];
        std::snprintf(buf, sizeof buf, "; least squares (LM) on the same features %s in %d iterations",
                      lm.ok() ? "converged" : "did NOT converge", lm.iterations);
        note += buf;
        if (!lm.ok()) note += ": " + lm.message;
        if (lm.ok()) {
          s.lm = lm.updated;
          if (!s.chosen.ok) s.chosen = {true, "lm", lm.updated, {}, 50e3};
        }
      } catch (const std::exception& e) {
        note += std::string("; least squares (LM) refused: ") + e.what();
      }
    }
    if (!feat.resonances_hz.empty()) s.chosen.first_resonance_hz = feat.resonances_hz.front();
    out.stages.push_back({"update (CMCM)", s.chosen.ok, note});
  } catch (const std::exception& e) {
    out.stages.push_back({"update (CMCM)", false, std::string("the seed's chain could not run: ") + e.what()});
  }
  return s;
}

// The output-error fit of the constants and Rayleigh β to the capture's
// samples (update/output_error.hpp): the pipeline's update. Never throws.
// The diagnosis of this capture runs in the output-error model (fewer than 3
// transient dut shots of its first drive, see diagnose_stage): the update's
// fit then also scans the catalogue's effects, once, for it.
int first_drive_shots(const acq::Capture& cap) {
  const acq::Shot* first = nullptr;
  int n = 0;
  for (const auto& s : cap.shots) {
    if (s.role != acq::Role::Dut || s.excitation == acq::Excitation::Sine) continue;
    if (!first) first = &s;
    n += s.excitation == first->excitation;
  }
  return n;
}

// … or a held-out capture of one or two shots (its attributes read here; an
// unreadable one is the diagnosis stage's to report).
bool diagnosed_by_output_error(const PipelineRequest& req, const acq::Capture& cap) {
  if (!req.diagnose) return false;
  const int n = first_drive_shots(cap);
  if (n == 0) return false;
  if (n < 3) return true;
  if (req.heldout_capture.empty()) return false;
  try {
    acq::ContainedReadOptions ro;
    ro.read.load_samples = false;
    ro.read.skip_invalid_shots = true;
    const auto ho = req.replay_contained ? acq::read_capture_contained(req.heldout_capture, ro)
                                         : acq::read_capture(req.heldout_capture, ro.read);
    return first_drive_shots(ho) < 3;
  } catch (const std::exception&) {
    return false;
  }
}

std::vector<std::string> scanned_effects(const PipelineRequest& req) {
  return req.gap_candidates.empty() ? update::supported_gap_effects() : req.gap_candidates;
}

std::optional<update::OeResult> output_error_stage(const PipelineRequest& req, const acq::Capture& cap,
                                                   const CaptureModel& cm, PipelineResult& out) {
  CaptureFitRequest cr;
  cr.material = req.material;
  cr.isotropic = req.isotropic;
  cr.options = req.oe_options;
  if (req.use_calibration) cr.fixture = out.fixture;
  if (diagnosed_by_output_error(req, cap)) cr.options.scan_effects = scanned_effects(req);
  try {
    const CaptureFit f = fit_capture(cap, cr, cm);
    const auto& r = f.result;
    int ok = 0;
    for (const auto& p : r.parameters) ok += p.status == "ok";
    char note[320];
    std::snprintf(note, sizeof note,
                  "output-error fit of %d shot(s) %s: chi2/dof %.3g (limit %.3g), %d of %zu constants ok, "
                  "%d FE port models%s%s",
                  r.shots_used, r.ok() ? "converged" : "did NOT converge", r.chi2_per_dof, r.chi2_limit, ok,
                  r.parameters.size(), r.evaluations, r.message.empty() ? "" : ": ",
                  r.message.c_str());
    out.stages.push_back({"update (output-error)", r.ok(), note});
    if (r.ok() && r.lack_of_fit) {
      char w[320];
      if (r.chi2_per_dof > r.chi2_limit)
        std::snprintf(w, sizeof w, "the output-error fit does not explain the capture (chi2/dof %.3g)", r.chi2_per_dof);
      else
        std::snprintf(w, sizeof w,
                      "the output-error fit does not explain the capture in %.3g-%.3g kHz (residual %.3g times "
                      "the noise there, chance 1e%.1f)",
                      r.band_lo_hz / 1e3, r.band_hi_hz / 1e3, r.band_excess, r.band_log10_p);
      out.warnings.push_back(std::string(w) +
                             ": its constants are marked not identifiable; the gap diagnosis looks for the cause");
    }
    out.output_error = r;
    out.output_error_excitation = f.excitation;
    return r;
  } catch (const std::exception& e) {
    out.stages.push_back({"update (output-error)", false, e.what()});
    return std::nullopt;
  }
}

// The first electrically active short-circuit mode of the model (the
// diagnosis' damping reference when the estimate found no resonance).
double first_active_mode_hz(model::ModalSolver& solver, const model::PiezoMaterialE& m) {
  model::ModalOptions mo;
  mo.n_modes = 12;
  const auto port = solver.port_model(m, mo);
  double wmax = 0;
  for (const auto& md : port.modes)
    if (!md.residual && md.omega > 0) wmax = std::max(wmax, md.participation * md.participation / (md.omega * md.omega));
  for (const auto& md : port.modes)
    if (!md.residual && md.omega > 0 && md.participation * md.participation / (md.omega * md.omega) >= 0.05 * wmax)
      return md.omega / (2 * M_PI);
  return 50e3;
}

// The parameter rows: the pipeline's update beside the seed's chain and the
// output-error fit; the simulated bench's truth for the demo only.
void parameter_rows(const update::TubeParams& p0, const UpdateOutcome& u, const SeedUpdate& seed,
                    const std::optional<update::OeResult>& oe, const drivers::sim::SimBench* sim,
                    PipelineResult& out) {
  std::map<std::string, double> truth;
  if (sim)
    for (const auto& [k, v] : sim->physics().truth()) truth[k] = v;
  auto value = [](const update::TubeParams& t, const std::string& n) {
    if (n == "YE11") return t.y_e11;
    if (n == "nu12") return t.nu12;
    if (n == "d31") return t.d31;
    return t.eps_t33 / model::kEps0;
  };
  for (const std::string n : {"YE11", "nu12", "d31", "epsT33_rel"}) {
    ParamRow row;
    row.name = n;
    row.unit = n == "YE11" ? "Pa" : n == "d31" ? "C/N" : "-";
    row.original = value(p0, n);
    row.updated = u.ok ? value(u.updated, n) : NAN;
    if (truth.count(n)) row.truth = truth[n];
    if (seed.cmcm) row.cmcm = value(*seed.cmcm, n);
    else if (seed.chosen.ok) row.cmcm = value(seed.chosen.updated, n);  // the seed's chain ended in LM
    if (seed.lm) row.lm = value(*seed.lm, n);
    if (oe)
      for (const auto& p : oe->parameters)
        if (p.name == n) {
          row.oe = p.value;
          row.oe_sigma = p.sigma;
          row.oe_status = p.status;
        }
    if (u.method == "output-error") {
      row.sigma = row.oe_sigma;
      row.status = row.oe_status;
    } else if (u.ok) {
      row.status = "ok (seed's chain, no sigma)";
    }
    out.params.push_back(row);
  }
}

// Transient dut shots of one excitation kind (the fit's, or any other).
std::vector<const acq::Shot*> dut_shots(const acq::Capture& cap, std::optional<acq::Excitation> kind, bool other) {
  std::vector<const acq::Shot*> v;
  for (const auto& s : cap.shots) {
    if (s.role != acq::Role::Dut || s.excitation == acq::Excitation::Sine) continue;
    if (kind && ((s.excitation == *kind) == other)) continue;
    v.push_back(&s);
  }
  return v;
}

update::GapData gap_data(const acq::Capture& cap, const std::vector<const acq::Shot*>& shots, double floor,
                         const std::string& what) {
  std::vector<dsp::DividerRecord> recs;
  for (const auto* s : shots) recs.push_back(acq::divider_record(cap, *s));
  dsp::ShotEnsembleOptions o;
  o.fmin_hz = 1e3;
  o.fmax_hz = std::min(120e3, shots.front()->sample_rate_hz / 4);
  o.linear_drive = true;  // the bench's AWG, as Prony's ramp_onset (estimate())
  const auto e = dsp::impedance_shot_ensemble(recs, o);
  update::GapData d;
  for (Eigen::Index i = 0; i < e.f_hz.size(); ++i) {
    d.f_hz.push_back(e.f_hz[i]);
    d.z_ohm.push_back(e.z_ohm[i]);
    d.sigma_log_mag.push_back(std::hypot(e.sigma_log_mag[i], floor));
    d.sigma_phase.push_back(std::hypot(e.sigma_phase[i], floor));
  }
  d.description = what + ": " + std::to_string(e.shots) + " shots, " + std::to_string(d.size()) + " frequencies";
  return d;
}

// The fixture quantities as effects of the catalogue (model/effects.hpp),
// clamped to its physical bounds (a lead resistance measured at -0.01 ohm is 0).
std::vector<update::MeasuredEffect> measured_effects(const dsp::FixtureCalibration& f, const std::string& how) {
  std::vector<update::MeasuredEffect> v;
  auto add = [&](const char* name, const std::optional<double>& val, const std::optional<double>& sig) {
    if (!val) return;
    const auto* info = model::find_effect(name);
    v.push_back({name, std::clamp(*val, info->lower, info->upper), sig.value_or(0.0),
                 "fixture calibration (" + how + ")"});
  };
  add("parallel_capacitance", f.fixture_capacitance_f, f.fixture_capacitance_sigma_f);
  add("series_resistance", f.lead_resistance_ohm, f.lead_resistance_sigma_ohm);
  add("r1_tolerance", f.r1_error, f.r1_error_sigma);
  add("channel_skew", f.skew_s, f.skew_sigma_s);
  return v;
}

// The curves of a diagnosis made in the output-error model (plots, GUI):
// ln(Z_meas/Z_model) on the FFT ratio of the first shot (first-differenced,
// 1 kHz to min(120 kHz, fs/4)), the noise band from each channel's white
// noise (pretrigger, else high-pass estimate) propagated per bin; the model
// is the bench's forward model with the base constants, and with the
// verdict's effect and the constants refitted with it.
void output_error_gap_curves(const acq::Capture& cap, const acq::Shot& shot, const CaptureModel& cm,
                             const update::OeResult& r, const update::OeOptions& oo, update::GapDiagnosis& d) {
  const dsp::DividerRecord rec = acq::divider_record(cap, shot);
  const std::size_t pre = rec.pretrigger_samples < rec.v1.size() ? rec.pretrigger_samples : 0;
  const std::size_t n = rec.v1.size() - pre;
  if (n < 64) return;
  auto mean_of = [&](std::span<const double> x) {
    double m = 0;
    for (std::size_t i = 0; i < pre; ++i) m += x[i];
    return pre ? m / double(pre) : 0.0;
  };
  auto noise_of = [&](std::span<const double> x) {
    if (pre >= 64) {
      const double m = mean_of(x);
      double q = 0;
      for (std::size_t i = 0; i < pre; ++i) q += (x[i] - m) * (x[i] - m);
      return std::sqrt(q / double(pre - 1));
    }
    return dsp::estimate_noise_std(Eigen::Map<const Eigen::VectorXd>(x.data(), static_cast<Eigen::Index>(x.size())));
  };
  const double s1 = noise_of(rec.v1), s2 = noise_of(rec.v2), m1 = mean_of(rec.v1), m2 = mean_of(rec.v2);
  Eigen::VectorXd d1(static_cast<Eigen::Index>(n)), d2(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {  // first differences from t = 0 (the idle level before it)
    const double a = rec.v1[pre + i] - m1, b = rec.v2[pre + i] - m2;
    const double a0 = i ? rec.v1[pre + i - 1] - m1 : 0.0, b0 = i ? rec.v2[pre + i - 1] - m2 : 0.0;
    d1[static_cast<Eigen::Index>(i)] = a - a0;
    d2[static_cast<Eigen::Index>(i)] = b - b0;
  }
  const Eigen::VectorXcd x1 = dsp::rfft(d1, n), x2 = dsp::rfft(d2, n);
  const double fs = rec.sample_rate_hz, r1 = rec.r1_ohm, fmax = std::min(120e3, fs / 4);
  std::vector<double> f;
  std::vector<std::complex<double>> zm;
  std::vector<double> var;
  for (Eigen::Index k = 1; k < x1.size(); ++k) {
    const double fk = fs * double(k) / double(n);
    if (fk < 1e3 || fk > fmax) continue;
    const std::complex<double> xi = x1[k] - x2[k];
    if (std::abs(xi) == 0.0 || std::abs(x2[k]) == 0.0) continue;
    f.push_back(fk);
    zm.push_back(r1 * x2[k] / xi);
    const double dd = 4.0 * std::pow(std::sin(M_PI * double(k) / double(n)), 2) * double(n);
    var.push_back(dd * (s2 * s2 * std::norm(1.0 / x2[k] + 1.0 / xi) + s1 * s1 * std::norm(1.0 / xi)));
  }
  if (f.size() < 2) return;
  auto curve = [&](const update::TubeParams& p, const update::OeLoss& loss,
                   const model::EffectSet& fx) {
    model::ModalOptions mo = oo.modal;
    mo.end_mass_fraction = fx.mass_loading;
    const auto port = cm.solver->port_model(cm.cls.e_form(p), mo);
    const auto z = model::bench_impedance(port, {0.0, loss.beta_s}, fx, r1, f, loss.eta);
    update::GapCurve c;
    for (std::size_t i = 0; i < f.size(); ++i) {
      const auto l = std::log(zm[i] / z[i]);
      c.f_hz.push_back(f[i]);
      c.residual_db.push_back(20.0 / std::log(10.0) * l.real());
      c.residual_deg.push_back(180.0 / M_PI * std::remainder(l.imag(), 2 * M_PI));
      const double sd = std::sqrt(0.5 * var[i]);
      c.sigma_db.push_back(20.0 / std::log(10.0) * sd);
      c.sigma_deg.push_back(180.0 / M_PI * std::min(sd, M_PI));
      c.measured_abs_ohm.push_back(std::abs(zm[i]));
    }
    return c;
  };
  d.before = curve(r.updated, r.loss(), r.effect_set);
  d.after = d.before;
  if (!d.steps.empty())
    for (const auto& e : r.effects)  // the fit with the verdict's effect: its constants, β and effects
      if (e.name == d.steps.front().name && std::isfinite(e.value))
        d.after = curve(e.material, e.loss(), e.effect_set);
}

void diagnose_stage(const PipelineRequest& req, const acq::Capture& cap, const CaptureModel& cm,
                    const acq::Capture* heldout_cap, const UpdateOutcome& u, PipelineResult& out,
                    const Stages& progress, const std::atomic<bool>& cancel) {
  auto fit_shots = dut_shots(cap, std::nullopt, false);
  if (fit_shots.empty()) throw std::invalid_argument("gap diagnosis: the capture holds no transient dut shot");
  const acq::Excitation kind = fit_shots.front()->excitation;
  fit_shots = dut_shots(cap, kind, false);
  std::vector<const acq::Shot*> ho_shots;
  const acq::Capture* ho_cap = &cap;
  std::string ho_what;
  if (heldout_cap) {
    ho_cap = heldout_cap;
    ho_shots = dut_shots(*heldout_cap, std::nullopt, false);
    ho_what = "held-out capture " + out.heldout_path;
  } else if (auto other = dut_shots(cap, kind, true); other.size() >= 3) {
    ho_shots = other;
    ho_what = "held-out shots of another excitation";
  } else if (fit_shots.size() >= 6) {
    std::vector<const acq::Shot*> even, odd;
    for (std::size_t i = 0; i < fit_shots.size(); ++i) (i % 2 ? odd : even).push_back(fit_shots[i]);
    fit_shots = even;
    ho_shots = odd;
    ho_what = "held-out odd-numbered shots";
  }
  if (fit_shots.size() < 3 || (heldout_cap && ho_shots.size() < 3)) {
    // One or two shots: the noise of Z(f) cannot be measured from repeats
    // (nor is it Gaussian per bin at a few percent): the diagnosis runs in the
    // output-error model instead, each effect a sixth parameter of the fit —
    // and so it does for a held-out capture of one or two shots, which the
    // output-error model predicts from its own v1.
    // The update's fit scanned the effects already (output_error_stage); a
    // fit of its own only where that one is missing.
    const update::OeResult* r = out.output_error && out.output_error->ok() &&
                                        out.output_error->effects.size() == scanned_effects(req).size()
                                    ? &*out.output_error
                                    : nullptr;
    std::optional<CaptureFit> own;
    CaptureFitRequest cr;
    cr.material = req.material;
    cr.isotropic = req.isotropic;
    cr.options = req.oe_options;
    if (req.use_calibration) cr.fixture = out.fixture;
    cr.options.scan_effects = scanned_effects(req);
    if (!r) {
      progress(0.75, "diagnose: the catalogue's effects in the output-error model");
      own = fit_capture(cap, cr, cm);
      if (!own->result.ok())
        throw std::runtime_error("gap diagnosis: the output-error fit did not converge: " + own->result.message);
      r = &own->result;
    }
    const std::string drive = own ? own->excitation : out.output_error_excitation;
    const std::string fit_what = "fit data: " + std::to_string(r->shots_used) + " " + drive + " shot(s)";
    update::GapDiagnosis d;
    if (heldout_cap) {
      progress(0.9, "diagnose: predicting the held-out capture");
      update::OeHeldout ho;
      std::string ho_drive;
      ho.data = capture_oe_data(*heldout_cap, cr.fixture, &ho_drive);
      ho.description = "held-out capture " + out.heldout_path + ", " + std::to_string(ho.data.shots.size()) + " " +
                       ho_drive + " shot(s)";
      d = update::gap_from_output_error(*r, fit_what, *cm.solver, cm.cls, ho, cr.options);
    } else {
      d = update::gap_from_output_error(*r, fit_what);
    }
    output_error_gap_curves(cap, *fit_shots.front(), cm, *r, cr.options, d);
    char note[240];
    std::snprintf(note, sizeof note, "output-error model, %d shot(s): chi2/dof %.2f; verdict: %s",
                  r->shots_used, r->chi2_per_dof, d.verdict_effect.c_str());
    out.stages.push_back({"diagnose", true, note});
    out.verdict = d.verdict;
    out.diagnosis = std::move(d);
    return;
  }
  const update::GapData fit = gap_data(cap, fit_shots, req.gap_floor, "fit data");
  std::optional<update::GapData> ho;
  if (ho_shots.size() >= 3) ho = gap_data(*ho_cap, ho_shots, req.gap_floor, ho_what);
  else out.warnings.push_back("gap diagnosis without held-out data (fewer than 3 other shots)");

  model::ModalSolver& solver = *cm.solver;
  const auto& cls = cm.cls;
  update::GapOptions go;
  go.candidates = req.gap_candidates;
  if (out.fixture) go.measured = measured_effects(*out.fixture, out.fixture_model);
  go.damping_ref_hz = u.first_resonance_hz;
  go.other_starts = {cm.p0};  // where the update started
  auto d = update::diagnose_gap(
      solver, cls, u.updated, u.damping, cap.setup.divider_r1_ohm, fit, ho ? &*ho : nullptr, go,
      [&](double f, const std::string& s) { progress(0.7 + 0.29 * f, s); }, &cancel);
  char note[200];
  std::snprintf(note, sizeof note, "gap chi2/dof %.2f on %s%s; verdict: %s", d.gap_fit,
                fit.description.c_str(), ho ? (", held-out " + std::to_string(d.gap_heldout.value_or(0)).substr(0, 5)).c_str() : "",
                d.verdict_effect.c_str());
  out.stages.push_back({"diagnose", true, note});
  out.verdict = d.verdict;
  out.diagnosis = std::move(d);
}

}  // namespace

PipelineResult run_pipeline(const PipelineRequest& req, const std::function<void(const PipelineProgress&)>& cb,
                            const std::atomic<bool>& cancel) {
  PipelineResult out;
  Stages progress{cb};
  std::shared_ptr<drivers::sim::SimBench> sim;
  acq::Capture cap = acquire(req, out, progress, cancel, sim);
  if (cancel) return out;
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
  else if (z) seed = seed_update_stage(req, cm, *z, out);
  else out.stages.push_back({"update (CMCM)", false, "needs the impedance estimate"});
  const std::string seed_note = out.stages.back().note;
  if (cancel) return out;
  progress(0.62, "update: output-error fit");
  const auto oe = output_error_stage(req, cap, cm, out);
  const std::string oe_note = out.stages.back().note;
  if (cancel) return out;

  // The pipeline's update: the output-error fit where it converged (its
  // constants carry sigma and status), else the seed's chain.
  UpdateOutcome u;
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
                           ") is used, without sigma");
  }
  out.update_method = u.ok ? u.method : "";
  {
    std::string note;
    if (u.ok) {
      note = u.method == "output-error" ? "the output-error fit's constants and beta (with sigma)"
                                        : u.method == "cmcm" ? "the seed's extended CMCM (no sigma)"
                                                             : "least squares (LM) on the seed's features (no sigma)";
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

}  // namespace piezo::ui
