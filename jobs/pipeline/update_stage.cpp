// The pipeline's room (jobs/pipeline), update stage: the seed's chain
// (extended CMCM, LM) on the estimate's features, the output-error fit of the
// capture, the damping of the model curves and the parameter rows.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "dsp/probability_text.hpp"
#include "acquisition/contained_read.hpp"
#include "acquisition/capture_file.hpp"
#include "jobs/pipeline/stages.hpp"
#include "jobs/seed_features.hpp"
#include "model/harmonic.hpp"
#include "model/material_spec.hpp"
#include "update/gap_diagnosis.hpp"
#include "update/feature_update.hpp"
#include "update/rayleigh.hpp"

namespace piezo::jobs::detail {

namespace {

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

}  // namespace

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

SeedUpdate seed_update_stage(const PipelineRequest& req, const acq::Capture& cap, const CaptureModel& cm,
                             const dsp::ImpedanceResult& z, PipelineResult& out) {
  // The seed's chain on the estimate's features (issue 40): only those inside
  // the drive's band and the model's mode range, each with its σ (the port
  // fit's for the first three pairs), and an honest status
  // (update/feature_update.hpp): a method's answer is used only when it is
  // physical and reproduces the features it was given.
  SeedUpdate s;
  try {
    const auto drive = capture_drive_band(cap);
    const double band_hi = z.f_hz.size() ? z.f_hz.maxCoeff() : 0.0;
    // The capacitance's σ also holds the chain's tolerances the output-error fit
    // states (R1, channel gain, Cp; a measured fixture's are already corrected for).
    dsp::ImpedanceFeatures zf = z.features;
    if (zf.capacitance_f > 0 && std::isfinite(zf.capacitance_sigma_f) && !(req.use_calibration && out.fixture)) {
      const auto& o = req.oe_options;
      const double c = zf.capacitance_f;
      zf.capacitance_sigma_f = std::hypot(zf.capacitance_sigma_f,
                                          c * std::sqrt(o.r1_rel_sigma * o.r1_rel_sigma + o.gain_rel_sigma * o.gain_rel_sigma +
                                                        (o.cp_sigma_f / c) * (o.cp_sigma_f / c)));
    }
    const SeedFeatures sf = select_seed_features(zf, band_hi, drive, cm);
    auto describe = [](const char* name, const update::FeatureUpdate& u) {
      std::string n = std::string(name) + " " + (u.ok() ? "converged" : "refused (" + u.check.status + ")");
      if (u.cmcm) {
        char buf[160];
        std::snprintf(buf, sizeof buf, ": %d elastic + %d piezo iterations in %d sweeps", u.cmcm->iterations_elastic,
                      u.cmcm->iterations_piezo, u.cmcm->sweeps);
        n += buf;
      } else if (u.lm) {
        n += ": " + std::to_string(u.lm->iterations) + " iterations";
      }
      if (!u.ok()) n += "; " + u.check.reason;
      return n;
    };
    const auto r = update::update_from_features(*cm.tube, *cm.solver, cm.cls, cm.p0, sf.features, sf.band,
                                                update::FeatureMethod::cmcm, {}, sf.no_features);
    std::string note = describe("extended CMCM", r);
    s.cmcm_run = r;
    if (r.ok()) {
      s.cmcm = r.updated;
      s.chosen = {true, "cmcm", r.updated, {}, 50e3};
    }
    if (!r.ok() || req.compare_lm) {
      // Second, independent updater on the same features (update/least_squares.hpp):
      // no mode-shape pairing, so a start far from the answer (mode veering, an
      // ambiguous MAC) does not stop it.
      const auto lm = update::update_from_features(*cm.tube, *cm.solver, cm.cls, cm.p0, sf.features, sf.band,
                                                   update::FeatureMethod::lm, {}, sf.no_features);
      note += "; " + describe("least squares (LM) on the same features", lm);
      s.lm_run = lm;
      if (lm.ok()) {
        s.lm = lm.updated;
        if (!s.chosen.ok) s.chosen = {true, "lm", lm.updated, {}, 50e3};
      }
    }
    if (!s.chosen.ok) s.refused = note;
    if (!sf.features.resonances_hz.empty()) s.chosen.first_resonance_hz = sf.features.resonances_hz.front();
    out.stages.push_back({"update (CMCM)", s.chosen.ok, note});
  } catch (const std::exception& e) {
    out.stages.push_back({"update (CMCM)", false, std::string("the seed's chain could not run: ") + e.what()});
    s.refused = e.what();
  }
  return s;
}

namespace {

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

}  // namespace

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
                      "the noise there, chance %s)",
                      r.band_lo_hz / 1e3, r.band_hi_hz / 1e3, r.band_excess,
                      dsp::probability_text(r.band_log10_p).c_str());
      out.warnings.push_back(std::string(w) +
                             ": its constants are marked not identifiable; the gap diagnosis looks for the cause");
    }
    // Issue 33: the bench's slow disturbances modelled, and shots that disagree.
    if (r.baseline.modelled || r.baseline.pink) {
      char w[320];
      std::snprintf(w, sizeof w, "bench disturbances modelled as nuisance (not effects):%s%s%s",
                    r.baseline.modelled ? " baseline wander (offset, slope to degree 3" : "",
                    r.baseline.modelled ? (r.baseline.harmonics > 0 ? ", mains hum) projected out" : ") projected out")
                                        : "",
                    r.baseline.pink ? (r.baseline.modelled ? "; 1/f noise weighted as noise" : " 1/f noise weighted as noise")
                                    : "");
      out.warnings.push_back(w);
    }
    if (r.shot_consistency.tested && !r.shot_consistency.consistent)
      out.warnings.push_back("non-stationary between shots: " + r.shot_consistency.summary);
    if (r.shot_consistency.aligned) out.warnings.push_back("shots aligned for trigger jitter before averaging");
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
    } else if (u.ok) {  // the seed's chain, where it holds (issue 40): with its sigma
      const auto& run = u.method == "cmcm" ? seed.cmcm_run : seed.lm_run;
      row.status = "ok (seed's chain)";
      if (run)
        for (const auto& c : run->check.constants)
          if (c.name == n) {
            if (std::isfinite(c.sigma)) row.sigma = c.sigma;
            row.status = c.status + " (seed's chain)";
          }
    }
    out.params.push_back(row);
  }
}

}  // namespace piezo::jobs::detail
