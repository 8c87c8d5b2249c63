#include "jobs/pipeline/capture_mode_figures.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "dsp/circuit_adequacy.hpp"
#include "update/model_figures.hpp"

namespace piezo::jobs {

namespace {

double mean_diameter(const acq::Capture& cap, std::string& source) {
  const auto g = cap.setup.geometry();
  const bool given = cap.setup.inner_diameter_m && cap.setup.outer_diameter_m;
  source = given ? "capture /setup" : "the project's default tube (not in the capture)";
  return 0.5 * (g.inner_diameter_m + g.outer_diameter_m);
}

dsp::Uncertain u(const dsp::Figure& f) { return {f.value, f.sigma}; }

}  // namespace

CaptureModeFigures capture_mode_figures(const acq::Capture& cap, const dsp::ImpedanceResult& z) {
  CaptureModeFigures out;
  dsp::ModeFigureOptions o;
  o.mean_diameter_m = mean_diameter(cap, out.mean_diameter_source);
  out.mean_diameter_m = o.mean_diameter_m;
  out.source = "BVD fit per mode to the " + z.method + " estimate";
  const Eigen::VectorXd sigma =
      z.z_sigma_ohm.size() == z.f_hz.size() ? z.z_sigma_ohm : Eigen::VectorXd();
  try {
    out.figures = dsp::mode_figures(z.f_hz, z.z_ohm, sigma, o);
  } catch (const std::invalid_argument& e) {  // a grid too short for figures: the impedance stands
    out.error = e.what();
  }
  return out;
}

CaptureModeFigures model_mode_figures(const acq::Capture& cap, const CaptureModel& cm, const update::OeResult& r,
                                      const CaptureModeFigures* measured) {
  CaptureModeFigures out;
  out.mean_diameter_m = mean_diameter(cap, out.mean_diameter_source);
  out.source = "updated FE model (output-error fit): its short- and open-circuit modes";
  update::ModelFigures mf;
  try {
    mf = update::model_figures(*cm.solver, cm.cls, r.updated, r.loss(), update::total_covariance_rel(r), 0,
                               r.band_hz, update::OeOptions{}.modal, r.effect_set);
  } catch (const std::exception& e) {
    out.error = std::string("the updated model's modes: ") + e.what();
    return out;
  }
  {  // plausibility of the model's figures (no data to check them against here)
    dsp::CircuitFit cf;
    cf.circuit = mf.circuit;
    cf.modes = mf.modes;
    cf.converged = r.ok();
    dsp::AdequacyOptions ao;
    ao.widen_sigma = false;
    ao.data_checks = false;
    Eigen::VectorXd band(2);
    band << 1.0, r.band_hz;
    dsp::assess_circuit_fit(band, Eigen::VectorXcd(), cf, ao);
    mf.modes = cf.modes;
  }
  auto& fr = out.figures;
  for (const auto& c : mf.modes) {
    dsp::ModeFigures m;
    m.fs_hz = u(c.fs_hz);
    m.fp_hz = u(c.fp_hz);
    m.fm_hz = u(c.fm_hz);
    m.fn_hz = u(c.fn_hz);
    m.k_eff = u(c.k_eff_ieee176);
    m.k_eff2 = {c.k_eff_ieee176.value * c.k_eff_ieee176.value, 2 * c.k_eff_ieee176.value * c.k_eff_ieee176.sigma};
    m.qm_branch = u(c.qm_branch);
    m.qm_bandwidth = u(c.qm_bandwidth);
    m.r1_ohm = u(c.r1_ohm);
    m.l1_h = u(c.l1_h);
    m.c1_f = u(c.c1_f);
    m.c0_f = u(mf.c0_f);
    m.frequency_constant_hz_m = {c.fs_hz.value * out.mean_diameter_m, c.fs_hz.sigma * out.mean_diameter_m};
    m.window_lo_hz = c.window_lo_hz;
    m.window_hi_hz = c.window_hi_hz;
    if (!(m.window_hi_hz > m.window_lo_hz) && c.fs_hz.value > 0) {
      // The model's mode has no fit window: its resonance neighbourhood, the
      // wider of fs-fp and the -3 dB bandwidth, 1.5 times on each side (the
      // admittance-plane plot draws the estimate and the branch there).
      const double fs = c.fs_hz.value, fp = std::isfinite(c.fp_hz.value) ? c.fp_hz.value : fs;
      const double bw = c.qm_branch.value > 0 ? fs / c.qm_branch.value : 0.0;
      const double w = 1.5 * std::max(fp - fs, bw);
      if (w > 0) {
        m.window_lo_hz = std::max(0.5 * fs, fs - w);
        m.window_hi_hz = fp + w;
      }
    }
    // The branch itself (the admittance-plane plot, jobs/mode_nyquist.hpp).
    m.fit.p = {c.r1_ohm.value, c.l1_h.value, c.c1_f.value, mf.c0_f.value};
    m.fit.converged = r.ok();
    m.fit.weighted = true;
    m.fit.chi2_per_dof = r.chi2_per_dof;  // the output-error fit's, of the samples
    m.status = c.status;
    m.reasons = c.reasons;
    if (!std::isfinite(c.fp_hz.value))
      m.notes.push_back("a weak mode inside a stronger one's fs-fp interval: no parallel resonance of its own");
    fr.modes.push_back(std::move(m));
  }
  for (std::size_t k = 0; k < fr.modes.size(); ++k)
    if (std::isfinite(fr.modes[k].k_eff.value) &&
        (fr.hoop_mode < 0 || fr.modes[k].k_eff.value > fr.modes[static_cast<std::size_t>(fr.hoop_mode)].k_eff.value))
      fr.hoop_mode = static_cast<int>(k);
  if (fr.hoop_mode >= 0) fr.frequency_constant_hz_m = fr.modes[static_cast<std::size_t>(fr.hoop_mode)].frequency_constant_hz_m;
  fr.notes = mf.notes;
  fr.notes.push_back("figures of the updated FE model's modes within the fit's band (up to " +
                     std::to_string(static_cast<long>(r.band_hz)) + " Hz), sigma from the constants' covariance");
  if (r.lack_of_fit)
    fr.notes.push_back("the output-error model does not explain the capture: the figures are the model's, their "
                       "sigmas Birge-widened");
  // C^T at EN 50324-2's 1 kHz: Im Y/ω of the updated model (its σ that of the
  // static capacitance, relative: the same constants move both). The model
  // sees the capture through the output-error fit, whose baseline model keeps
  // a bench's slow disturbances out of it — the estimate's lowest bins do not
  // (a 2 ms record's 1 kHz is its second bin). tan δ stays the estimate's: the
  // five-parameter model has no dielectric loss.
  fr.reference_used_hz = 1000.0;
  const double w = 2 * std::numbers::pi * fr.reference_used_hz;
  const double ct = mf.circuit.admittance_without_rs(fr.reference_used_hz).imag() / w;
  fr.free_capacitance_f = {ct, ct * mf.free_capacitance_f.sigma / mf.free_capacitance_f.value};
  if (measured && measured->error.empty() && std::isfinite(measured->figures.tan_delta.value)) {
    fr.tan_delta = measured->figures.tan_delta;
    fr.notes.push_back("C^T the updated model's at " + std::to_string(static_cast<long>(fr.reference_used_hz)) +
                       " Hz; tan d measured on the impedance estimate at " +
                       std::to_string(static_cast<long>(measured->figures.reference_used_hz)) + " Hz");
  } else {
    fr.notes.push_back("C^T the updated model's at 1000 Hz; tan d not measured (no impedance estimate)");
  }
  return out;
}

}  // namespace piezo::jobs
