#include "jobs/figures_job.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <ostream>
#include <stdexcept>

#include "dsp/impedance_files/read_any.hpp"
#include "jobs/impedance_job.hpp"
#include "jobs/job_error.hpp"
#include "jobs/report/figure_png.hpp"

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

}  // namespace

FiguresJobResult run_figures(const FiguresRequest& req) {
  if (req.max_modes < 1) throw InputError("--modes must be >= 1");
  if (req.band_lo_hz < 0 || (req.band_hi_hz > 0 && !(req.band_hi_hz > req.band_lo_hz)))
    throw InputError("--band: LO:HI with 0 <= LO < HI");
  FiguresJobResult out;
  std::vector<double> f;
  std::vector<std::complex<double>> z;
  std::vector<double> zs;
  double hi_default = 0;
  if (is_hdf5(req.file)) {
    ImpedanceRequest ir;
    ir.file = req.file;
    ir.method = req.method;
    ir.uncertainty = "auto";
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
    if (!(req.band_hi_hz > 0))
      out.notes.push_back("band up to " + std::to_string(static_cast<long>(hi_default)) +
                          " Hz (1.5 x the estimate's highest anti-resonance; --band sets another)");
  } else {
    dsp::ImportedImpedance im;
    try {
      im = dsp::read_impedance_file(req.file);
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
  dsp::CircuitFitOptions opt;
  opt.max_branches = req.max_modes;
  opt.auto_magnitude_only = out.source == "file";  // a capture's estimate has a defined phase
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
      {"sigma", "1 sigma from the fit's covariance, inflated by chi2/dof when above 1 (lack of fit)"}};
  j["modes"] = nlohmann::json::array();
  for (std::size_t k = 0; k < fit.modes.size(); ++k) {
    const auto& m = fit.modes[k];
    nlohmann::json jm;
    jm["mode"] = k + 1;
    for (const auto& [name, f] : dsp::named_figures(m)) jm[name] = fig(*f);
    jm["window_hz"] = {num(m.window_lo_hz), num(m.window_hi_hz)};
    jm["points"] = m.points;
    jm["misfit_rel_rms"] = num(m.misfit_rel_rms);
    j["modes"].push_back(jm);
  }
  j["notes"] = r.notes;
  for (const auto& s : fit.notes) j["notes"].push_back(s);
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
  Series fm{"fitted network (" + std::to_string(r.fit.modes.size()) + " modes)", {}, {}, "#2ca02c", 2.0, false, false};
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
  figure.title = "figures: data and fitted equivalent circuit (fs red, fp violet)";
  figure.panels = {mag, ph};
  write_png(figure, png);
}

}  // namespace piezo::jobs
