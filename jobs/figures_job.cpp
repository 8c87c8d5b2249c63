#include "jobs/figures_job.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <ostream>
#include <stdexcept>

#include "acquisition/capture.hpp"
#include "dsp/circuit_adequacy.hpp"
#include "dsp/impedance_files/read_any.hpp"
#include "jobs/impedance_job.hpp"
#include "jobs/job_error.hpp"
#include "jobs/json/output_error_json.hpp"
#include "jobs/nominal_material.hpp"
#include "jobs/pipeline/capture_fit.hpp"
#include "jobs/report/plot_cairo.hpp"
#include "update/model_figures.hpp"

namespace piezo::jobs {

namespace {

bool is_hdf5(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open");
  char sig[8] = {};
  in.read(sig, 8);
  return in.gcount() == 8 && std::string(sig, 8) == std::string("\x89HDF\r\n\x1a\n", 8);
}

nlohmann::json fig(const dsp::Figure& f) {
  nlohmann::json j = {{"value", nullptr}, {"sigma", nullptr}};
  if (std::isfinite(f.value)) j["value"] = f.value;
  if (std::isfinite(f.sigma)) j["sigma"] = f.sigma;
  return j;
}

nlohmann::json num(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

// Relative RMS of the network against the data, over the points in [lo, hi]:
// of Z, of |Z| and of |Y|; and how many points.
struct Misfit {
  double z = dsp::kNaN, abs_z = dsp::kNaN, abs_y = dsp::kNaN;
  int points = 0;
};
Misfit misfit(const dsp::EquivalentCircuit& c, const Eigen::VectorXd& f, const Eigen::VectorXcd& z, double lo,
              double hi) {
  double sz = 0, sa = 0, sy = 0;
  Misfit m;
  for (Eigen::Index i = 0; i < f.size(); ++i) {
    if (f[i] < lo || f[i] > hi || !(std::abs(z[i]) > 0)) continue;
    const auto zf = c.impedance(f[i]);
    sz += std::norm(zf - z[i]) / std::norm(z[i]);
    sa += std::pow(std::abs(zf) / std::abs(z[i]) - 1, 2);
    sy += std::pow(std::abs(z[i]) / std::abs(zf) - 1, 2);
    ++m.points;
  }
  if (m.points) {
    m.z = std::sqrt(sz / m.points);
    m.abs_z = std::sqrt(sa / m.points);
    m.abs_y = std::sqrt(sy / m.points);
  }
  return m;
}

// --method oe: the output-error fit of the capture, then the updated model's
// figures (update/model_figures.hpp) within the fit's band (or --band).
void figures_from_output_error(const FiguresRequest& req, const acq::Capture& cap, FiguresJobResult& out,
                               double& band_hi) {
  const auto nm = nominal_material(req.material, cap.setup.material);
  if (nm.warning) out.warnings.push_back(*nm.warning);
  CaptureFitRequest fr;
  fr.material = nm.name;
  const CaptureModel model = capture_model(cap, fr.material, fr.isotropic);
  CaptureFit fit;
  try {
    fit = fit_capture(cap, fr, model);
  } catch (const std::invalid_argument& e) {
    throw InputError(req.file + ": " + e.what() + " (--method fft fits the circuit to the FFT estimate instead)");
  }
  const auto& r = fit.result;
  out.output_error = output_error_json(r, fit.excitation);
  if (!r.ok())
    throw InputError(req.file + ": the output-error fit did not converge (" + r.message +
                     "); no model to take figures from (--method fft fits the circuit to the FFT estimate)");
  band_hi = req.band_hi_hz > 0 ? req.band_hi_hz : r.band_hz;
  const auto mf = update::model_figures(*model.solver, model.cls, r.updated, r.loss(), update::total_covariance_rel(r),
                                        req.band_lo_hz, band_hi, fr.options.modal, r.effect_set);
  out.model_figures = true;
  out.format = "oe";
  out.quantity = "updated FE model (output-error fit of " + std::to_string(r.shots_used) + " " + fit.excitation +
                 " shot(s), chi2/dof " + std::to_string(r.chi2_per_dof) + ")";
  auto& cf = out.fit;
  cf.circuit = mf.circuit;
  cf.modes = mf.modes;
  cf.c0_f = mf.c0_f;
  cf.tan_delta = mf.tan_delta;
  cf.rs_ohm = {0.0, 0.0};
  cf.free_capacitance_f = mf.free_capacitance_f;
  cf.parameters = static_cast<int>(r.parameters.size());
  cf.chi2_per_dof = r.chi2_per_dof;  // of the samples, the fit's own
  cf.converged = r.ok();
  cf.notes = mf.notes;
  cf.notes.push_back("figures of the updated FE model's short- and open-circuit modes (" +
                     std::to_string(mf.port_models) + " FE port models: the answer and 2 per principal axis of the "
                     "constants' covariance, type-B tolerances included); the data shown are the capture's FFT ratio");
  if (r.lack_of_fit)
    out.warnings.push_back("the output-error model does not explain the capture (chi2/dof " +
                           std::to_string(r.chi2_per_dof) + "): the figures are the model's, their sigmas widened by "
                           "the Birge ratio; an effect the model lacks may bias them");
  for (const auto& p : r.parameters)
    if (p.status != "ok")
      out.warnings.push_back(p.name + " is not identifiable from this capture (" + p.reason +
                             "): the figures that depend on it carry its sigma");
}

}  // namespace

std::vector<std::string> figures_estimators() {
  return acq::builtin_estimators().keys([](const acq::EstimatorEntry& e) { return e.caps.transient_shots; });
}

FiguresJobResult run_figures(const FiguresRequest& req) {
  if (req.max_modes < 1) throw InputError("--modes must be >= 1");
  if (req.band_lo_hz < 0 || (req.band_hi_hz > 0 && !(req.band_hi_hz > req.band_lo_hz)))
    throw InputError("--band: LO:HI with 0 <= LO < HI");
  FiguresJobResult out;
  std::vector<double> f;
  std::vector<std::complex<double>> z;
  std::vector<double> zs;
  double hi_default = 0;
  bool magnitude_only = false;  // the file gives |Z| without its phase
  const bool capture = is_hdf5(req.file);
  if (!capture && !req.method.empty())
    throw InputError("--method " + req.method + " is for a capture (.h5): " + req.file + " is an impedance file");
  if (capture && !req.columns.empty())
    throw InputError("--columns names a table's columns: " + req.file + " is a capture (.h5)");
  const bool oe = capture && (req.method.empty() || req.method == "oe");
  if (capture && !oe) {
    const auto keys = figures_estimators();
    if (std::find(keys.begin(), keys.end(), req.method) == keys.end())
      throw InputError("--method " + req.method + ": expected oe, " + acq::join_keys(keys));
  }
  if (capture) {
    ImpedanceRequest ir;
    ir.file = req.file;
    ir.method = oe ? "fft" : req.method;
    ir.uncertainty = "auto";
    // The figures read the estimate, its σ and band only: the impedance command's
    // Kramers-Kronig, per-shot validity and stabilization checks change none of
    // them and are not run (a quarter of the command's time; issue 43).
    ir.no_kk = ir.no_validity = ir.no_stabilization = true;
    const auto r = run_impedance(ir);
    out.source = "capture";
    out.format = r.z.method;
    out.quantity = "impedance estimate of " + std::to_string(r.shots.size()) + " dut shot(s)";
    for (Eigen::Index i = 0; i < r.z.f_hz.size(); ++i) {
      f.push_back(r.z.f_hz[i]);
      z.push_back(r.z.z_ohm[i]);
      if (r.z.z_sigma_ohm.size() == r.z.f_hz.size()) zs.push_back(r.z.z_sigma_ohm[i]);
    }
    if (zs.size() != f.size()) {
      zs.clear();
      out.notes.push_back("the estimate carries no per-point uncertainty: relative weights, the residual sets the scale");
    }
    // The band the estimate supports: by default up to 1.5 x the highest
    // anti-resonance it shows (an FFT ratio runs to fs/4, far past the drive's
    // energy; give --band for another).
    hi_default = r.band_hz;
    if (!r.z.features.antiresonances.empty())
      hi_default = std::min(hi_default, 1.5 * r.z.features.antiresonances.back().f_hz);
    if (oe)
      figures_from_output_error(req, r.capture, out, hi_default);
    else if (!(req.band_hi_hz > 0))
      out.notes.push_back("band up to " + std::to_string(static_cast<long>(hi_default)) +
                          " Hz (1.5 x the estimate's highest anti-resonance; --band sets another)");
  } else {
    dsp::ImportedImpedance im;
    try {
      dsp::ImpedanceReadOptions ro;
      ro.columns = req.columns;
      im = dsp::read_impedance_file(req.file, ro);
    } catch (const std::invalid_argument& e) {
      throw InputError(e.what());
    } catch (const std::runtime_error& e) {
      throw InputError(e.what());
    }
    out.source = "file";
    out.format = im.format_name;
    out.quantity = im.quantity;
    out.notes = im.notes;
    f = im.f_hz;
    z = im.z_ohm;
    magnitude_only = im.magnitude_only;
    if (im.abs_sigma_ohm.size() == im.size() && im.phase_sigma_rad.size() == im.size())
      for (std::size_t i = 0; i < im.size(); ++i)
        zs.push_back(std::hypot(im.abs_sigma_ohm[i], std::abs(im.z_ohm[i]) * im.phase_sigma_rad[i]));
  }
  const double lo = req.band_lo_hz, hi = req.band_hi_hz > 0 ? req.band_hi_hz : hi_default;
  std::vector<Eigen::Index> keep;
  for (std::size_t i = 0; i < f.size(); ++i)
    if (f[i] > 0 && f[i] >= lo && (!(hi > 0) || f[i] <= hi) && (zs.empty() || zs[i] > 0))
      keep.push_back(static_cast<Eigen::Index>(i));
  if (keep.size() < 8)
    throw InputError(req.file + ": " + std::to_string(keep.size()) + " points in the band (at least 8 needed)");
  const auto n = static_cast<Eigen::Index>(keep.size());
  out.f_hz.resize(n);
  out.z_ohm.resize(n);
  if (!zs.empty()) out.z_sigma_ohm.resize(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>(keep[static_cast<std::size_t>(k)]);
    out.f_hz[k] = f[i];
    out.z_ohm[k] = z[i];
    if (!zs.empty()) out.z_sigma_ohm[k] = zs[i];
  }
  if (out.model_figures) {  // the network is the model's: its misfit against the capture's estimate
    auto& cf = out.fit;
    cf.points = static_cast<int>(n);
    cf.weighted = out.z_sigma_ohm.size() == n;
    const auto all = misfit(cf.circuit, out.f_hz, out.z_ohm, 0, std::numeric_limits<double>::infinity());
    cf.misfit_rel_rms = all.z;
    cf.misfit_abs_rel_rms = all.abs_z;
    cf.misfit_admittance_abs_rel_rms = all.abs_y;
    for (auto& m : cf.modes) {
      const auto w = misfit(cf.circuit, out.f_hz, out.z_ohm, m.window_lo_hz, m.window_hi_hz);
      m.misfit_rel_rms = w.z;
      m.points = w.points;
    }
    {  // the model's figures are not a fit to the estimate: plausibility only
      dsp::AdequacyOptions ao;
      ao.widen_sigma = false;
      ao.data_checks = false;
      ao.max_branches = req.max_modes;
      dsp::assess_circuit_fit(out.f_hz, out.z_ohm, cf, ao);
    }
    if (static_cast<int>(cf.modes.size()) > req.max_modes) {
      cf.notes.push_back("reported the " + std::to_string(req.max_modes) + " strongest of " +
                         std::to_string(cf.modes.size()) + " modes (--modes)");
      std::stable_sort(cf.modes.begin(), cf.modes.end(), [](const auto& a, const auto& b) {
        return a.k_eff_ieee176.value > b.k_eff_ieee176.value;
      });
      cf.modes.resize(static_cast<std::size_t>(req.max_modes));
      std::sort(cf.modes.begin(), cf.modes.end(),
                [](const auto& a, const auto& b) { return a.fs_hz.value < b.fs_hz.value; });
    }
    return out;
  }
  dsp::CircuitFitOptions opt;
  opt.max_branches = req.max_modes;
  opt.auto_magnitude_only = out.source == "file";  // a capture's estimate has a defined phase
  opt.magnitude_only = magnitude_only;
  try {
    out.fit = dsp::fit_equivalent_circuit(out.f_hz, out.z_ohm, out.z_sigma_ohm, opt);
  } catch (const std::invalid_argument& e) {
    throw InputError(req.file + ": " + e.what());
  }
  return out;
}

nlohmann::json figures_json(const FiguresRequest& req, const FiguresJobResult& r) {
  const auto& fit = r.fit;
  nlohmann::json j;
  j["file"] = req.file;
  j["source"] = r.source;
  j["format"] = r.format;
  j["quantity"] = r.quantity;
  j["points"] = fit.points;
  j["band_hz"] = {r.f_hz[0], r.f_hz[r.f_hz.size() - 1]};
  j["weighted"] = fit.weighted;
  j["magnitude_only"] = fit.magnitude_only;
  j["circuit"] = {{"c0_f", fig(fit.c0_f)},
                  {"tan_delta", fig(fit.tan_delta)},
                  {"rs_ohm", fig(fit.rs_ohm)},
                  {"free_capacitance_f", fig(fit.free_capacitance_f)},
                  {"branches", fit.circuit.branches.size()}};
  j["fit"] = {{"chi2", num(fit.chi2)},
              {"parameters", fit.parameters},
              {"chi2_per_dof", num(fit.chi2_per_dof)},
              {"bic", num(fit.bic)},
              {"converged", fit.converged},
              {"misfit_rel_rms", num(fit.misfit_rel_rms)},
              {"misfit_abs_rel_rms", num(fit.misfit_abs_rel_rms)},
              {"misfit_admittance_abs_rel_rms", num(fit.misfit_admittance_abs_rel_rms)}};
  j["definitions"] = {
      {"fs_hz, fp_hz", "IEEE 176 motional series resonance 1/(2 pi sqrt(L1 C1)) and the lossless network's parallel resonance"},
      {"fm_hz, fn_hz", "IEEE 176 frequencies of minimum and maximum |Z| of the fitted network"},
      {"fr_hz, fa_hz", "IEEE 176 zero-phase frequencies (null when the phase never reaches 0)"},
      {"k_eff_ieee176", "sqrt(1 - (fs/fp)^2), IEEE 176 effective (dynamic) coupling"},
      {"k_eff_en50324", "sqrt(1 - (fm/fn)^2), EN 50324-2's form from the |Z| extrema"},
      {"qm_branch", "2 pi fs L1 / R1"},
      {"qm_bandwidth", "f_Gmax / (f2 - f1), conductance half-power points (EN 50324-2)"},
      {"sigma", "1 sigma from the fit's covariance (a file without per-point sigma: relative weights, the "
                "residual sets the scale; with them: inflated by chi2/dof when above 1), widened by the residual's "
                "correlation in the mode's window and by the offset from the data's own conductance, resistance and "
                "|Z| extrema where significant (sigma_notes say by how much)"},
      {"status", "ok, or unreliable with the reasons (misfit in the window, implausible values, the k_eff forms "
                 "disagreeing, a Q the grid or window cannot resolve, a resonance outside the data); an unreliable "
                 "figure never passes a limit"}};
  j["status"] = fit.status;
  j["status_reasons"] = fit.status_reasons;
  j["fit"]["noise_scatter_rel"] = num(fit.noise_scatter_rel);
  j["fit"]["residual_to_scatter"] = num(fit.residual_to_scatter);
  j["fit"]["residual_lag1"] = num(fit.residual_lag1);
  j["data_peaks"] = nlohmann::json::array();
  for (const auto& p : fit.data_peaks)
    j["data_peaks"].push_back({{"f_hz", p.f_hz}, {"prominence_s", p.prominence_s},
                               {"mode", p.mode >= 0 ? nlohmann::json(p.mode + 1) : nlohmann::json(nullptr)}});
  j["modes"] = nlohmann::json::array();
  for (std::size_t k = 0; k < fit.modes.size(); ++k) {
    const auto& m = fit.modes[k];
    nlohmann::json jm;
    jm["mode"] = k + 1;
    for (const auto& [name, f] : dsp::named_figures(m)) jm[name] = fig(*f);
    jm["window_hz"] = {num(m.window_lo_hz), num(m.window_hi_hz)};
    jm["points"] = m.points;
    jm["misfit_rel_rms"] = num(m.misfit_rel_rms);
    jm["status"] = m.status;
    jm["reasons"] = m.reasons;
    jm["sigma_notes"] = m.sigma_notes;
    j["modes"].push_back(jm);
  }
  j["notes"] = r.notes;
  for (const auto& s : fit.notes) j["notes"].push_back(s);
  if (r.model_figures) {
    j["figures_from"] = "updated FE model (output-error fit of the capture's samples)";
    j["definitions"]["fs_hz, fp_hz"] =
        "the updated FE model's short-circuit mode and the zero of its lossless susceptance (its open-circuit mode)";
    j["definitions"]["sigma"] =
        "1 sigma from the constants' covariance (Birge-widened under a lack of fit, type-B tolerances included)";
    j["definitions"]["misfit_rel_rms"] = "of the model against the capture's FFT-ratio estimate (its noise included)";
    j["output_error"] = r.output_error;
  }
  if (!r.warnings.empty()) j["warnings"] = r.warnings;
  return j;
}

void write_figures_csv(std::ostream& os, const FiguresJobResult& r) {
  os << "mode";
  if (!r.fit.modes.empty())
    for (const auto& [name, f] : dsp::named_figures(r.fit.modes[0])) os << ',' << name << ',' << name << "_sigma";
  os << ",misfit_rel_rms\n";
  os.precision(10);
  for (std::size_t k = 0; k < r.fit.modes.size(); ++k) {
    os << k + 1;
    for (const auto& [name, f] : dsp::named_figures(r.fit.modes[k])) os << ',' << f->value << ',' << f->sigma;
    os << ',' << r.fit.modes[k].misfit_rel_rms << '\n';
  }
}

void write_figures_plot(const FiguresJobResult& r, const std::filesystem::path& png) {
  using namespace report;
  Panel mag{"|Z|", "frequency [Hz]", "|Z| [ohm]", Scale::Log, Scale::Log, {}, {}, {}, {}, {}};
  Panel ph{"phase", "frequency [Hz]", "phase [deg]", Scale::Log, Scale::Linear, {}, std::pair(-95.0, 95.0), {}, {}, {}};
  Series dm{"data", {}, {}, "#1f1f7a", 1.2, false, true}, dp{"", {}, {}, "#1f1f7a", 1.2, false, true};
  for (Eigen::Index i = 0; i < r.f_hz.size(); ++i) {
    dm.x.push_back(r.f_hz[i]);
    dm.y.push_back(std::abs(r.z_ohm[i]));
    dp.x.push_back(r.f_hz[i]);
    dp.y.push_back(std::arg(r.z_ohm[i]) * 180.0 / std::numbers::pi);
  }
  // The fitted network on a dense log grid.
  Series fm{(r.model_figures ? "updated FE model (" : "fitted network (") + std::to_string(r.fit.modes.size()) +
                " modes)",
            {}, {}, "#2ca02c", 2.0, false, false};
  if (r.model_figures) dm.label = "the capture's FFT ratio";
  Series fpz{"", {}, {}, "#2ca02c", 2.0, false, false};
  const double a = r.f_hz[0], b = r.f_hz[r.f_hz.size() - 1];
  for (int i = 0; i <= 2000; ++i) {
    const double f = a * std::pow(b / a, i / 2000.0);
    const auto z = r.fit.circuit.impedance(f);
    fm.x.push_back(f);
    fm.y.push_back(std::abs(z));
    fpz.x.push_back(f);
    fpz.y.push_back(std::arg(z) * 180.0 / std::numbers::pi);
  }
  if (r.fit.magnitude_only) ph.title = "phase (not fitted: the data's phase cannot be trusted)";
  mag.series = {dm, fm};
  ph.series = {dp, fpz};
  for (const auto& m : r.fit.modes) {
    mag.markers.push_back({m.fs_hz.value, "#d62728"});
    if (std::isfinite(m.fp_hz.value)) mag.markers.push_back({m.fp_hz.value, "#9467bd"});
  }
  Figure figure;
  figure.title = r.model_figures ? "figures: the capture and its updated FE model (fs red, fp violet)"
                                 : "figures: data and fitted equivalent circuit (fs red, fp violet)";
  figure.panels = {mag, ph};
  write_png(figure, png);
}

}  // namespace piezo::jobs
