// The jobs' room (jobs/): model updating from impedance features (see
// update_features_job.hpp).
#include "jobs/update_features_job.hpp"

#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "jobs/job_error.hpp"
#include "jobs/report/plot_cairo.hpp"
#include "model/harmonic.hpp"
#include "model/material_presets.hpp"
#include "update/impedance_file.hpp"
#include "update/least_squares.hpp"
#include "update/rayleigh.hpp"
#include "update/updater.hpp"

namespace piezo::jobs {

namespace {

namespace pm = piezo::model;
namespace pu = piezo::update;

std::map<std::string, double> parse_set(const std::string& s) {
  std::map<std::string, double> kv;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item.empty()) continue;
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError("--set: expected key=value, got '" + item + "'");
    const std::string val = item.substr(eq + 1);
    std::size_t used = 0;
    double v = NAN;
    try {
      v = std::stod(val, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != val.size() || !std::isfinite(v))
      throw InputError("--set: bad number for " + item.substr(0, eq) + ": '" + val + "'");
    kv[item.substr(0, eq)] = v;
  }
  return kv;
}

nlohmann::json params_json(const pu::MaterialClass& cls, const pu::TubeParams& p) {
  nlohmann::json j = {
      {"YE11", p.y_e11}, {"nu12", p.nu12}, {"d31", p.d31}, {"epsT33_rel", p.eps_t33 / pm::kEps0}};
  try {
    const auto e = cls.e_summary(cls.coordinates(p), p.d31 < 0 ? -1 : 1);
    j["cE11"] = e.c_e11;
    j["cE12"] = e.c_e12;
    j["e31"] = e.e31;
    j["epsS33_rel"] = e.eps_s33 / pm::kEps0;
  } catch (const std::invalid_argument&) {
  }
  return j;
}

std::vector<std::complex<double>> model_impedance(pm::ModalSolver& solver,
                                                  const pm::PiezoMaterialE& m,
                                                  const std::vector<double>& f,
                                                  const pm::RayleighDamping& d) {
  pm::ModalOptions o;
  o.n_modes = 20;
  const auto port = solver.port_model(m, o);
  return pm::impedance_from_admittance(pm::admittance_modal(port, f, d));
}

// Figs 36-37: α1, α2 per elastic CMCM iteration and α3 per piezo iteration.
void write_history_plot(const pu::UpdateResult& r, bool seed, const std::string& file) {
  namespace rp = report;
  rp::Figure fig;
  fig.title = "Figs 36-37: CMCM correction coefficients per iteration";
  fig.subtitle = seed ? "the seed's procedure: one pass, i != j equations" : "our procedure: outer sweeps";
  fig.note = "final: alpha1 " + std::to_string(r.alpha1) + ", alpha2 " + std::to_string(r.alpha2) + ", alpha3 " +
             std::to_string(r.alpha3);
  rp::Panel el, pz;
  el.title = "elastic phase (resonances)";
  el.y_label = "alpha";
  pz.title = "piezoelectric phase (anti-resonances)";
  pz.x_label = "iteration";
  pz.y_label = "alpha3";
  rp::Series a1{"alpha1"}, a2{"alpha2"}, a3{"alpha3"};
  a2.colour = "#d62728";
  a3.colour = "#2ca02c";
  for (std::size_t k = 0; k < r.elastic_alpha_history.size(); ++k) {
    a1.x.push_back(static_cast<double>(k + 1));
    a1.y.push_back(r.elastic_alpha_history[k][0]);
    a2.x.push_back(static_cast<double>(k + 1));
    a2.y.push_back(r.elastic_alpha_history[k][1]);
  }
  for (std::size_t k = 0; k < r.piezo_alpha_history.size(); ++k) {
    a3.x.push_back(static_cast<double>(k + 1));
    a3.y.push_back(r.piezo_alpha_history[k]);
  }
  for (auto* s : {&a1, &a2, &a3}) s->points = s->x.size() < 40;
  el.series = {a1, a2};
  el.x_label = "iteration";
  pz.series = {a3};
  fig.panels = {el, pz};
  const std::filesystem::path path(file);
  if (path.extension() == ".svg")
    rp::write_svg(fig, path);
  else if (path.extension() == ".png")
    rp::write_png(fig, path);
  else
    throw InputError("--history-plot " + file + ": give a .png or .svg file name");
}

}  // namespace

UpdateFeaturesResult run_update_features(const UpdateFeaturesRequest& a) {
  if (a.method != "cmcm" && a.method != "lm" && a.method != "both")
    throw InputError("--method must be cmcm, lm or both");
  if (a.capacitance != "fe" && a.capacitance != "analytic")
    throw InputError("--capacitance must be fe or analytic");
  if (a.max_iterations < 1) throw InputError("--max-iterations must be >= 1");
  if (!(a.min_cross > 0.0 && a.min_cross < 1.0))
    throw InputError("--min-cross must be in (0, 1) (default 1e-3: pairs below it carry round-off only)");
  if (!a.history_plot.empty()) {
    const std::string ext = std::filesystem::path(a.history_plot).extension().string();
    if (ext != ".png" && ext != ".svg") throw InputError("--history-plot " + a.history_plot + ": give a .png or .svg file name");
  }
  const auto& preset = pm::find_preset(a.material.empty() ? "apc850" : a.material);
  pm::TubeGeometry geometry;
  geometry.density_kg_m3 = preset.density_kg_m3;

  // Features: file first, explicit options override.
  pu::MeasuredFeatures mf;
  std::optional<pu::ImpedanceCurve> curve;
  nlohmann::json measured;
  if (!a.file.empty()) {
    try {
      curve = pu::read_impedance_file(a.file);
    } catch (const std::runtime_error& e) {
      throw InputError(e.what());
    }
    const auto ex = pu::extract_features(*curve);
    mf = ex.features;
    measured["file"] = a.file;
    measured["low_z_phase_deg"] = ex.low_z_phase_deg;
  }
  if (!a.resonances.empty()) mf.resonances_hz = pu::parse_list(a.resonances);
  if (!a.antiresonances.empty()) mf.antiresonances_hz = pu::parse_list(a.antiresonances);
  if (!a.low_z.empty()) std::tie(mf.low_z_ohm, mf.low_z_hz) = pu::parse_ohm_at_hz(a.low_z);
  if (mf.resonances_hz.empty() || mf.antiresonances_hz.empty() || !(mf.low_z_ohm > 0))
    throw InputError("need an impedance file or --resonances, --antiresonances and --low-z");
  mf.validate();
  measured["resonances_hz"] = mf.resonances_hz;
  measured["antiresonances_hz"] = mf.antiresonances_hz;
  measured["low_z_ohm"] = mf.low_z_ohm;
  measured["low_z_hz"] = mf.low_z_hz;

  // Original model: the four sensitive parameters of the preset, --set overrides.
  pu::TubeParams p0 = pm::isotropic_params(preset.material);
  auto kv = parse_set(a.set);
  auto take = [&](const char* key, double& field, double scale = 1.0) {
    if (auto it = kv.find(key); it != kv.end()) {
      field = it->second * scale;
      kv.erase(it);
    }
  };
  take("YE11", p0.y_e11);
  take("nu12", p0.nu12);
  take("d31", p0.d31);
  take("epsT33", p0.eps_t33);
  take("epsT33_rel", p0.eps_t33, pm::kEps0);
  if (!kv.empty())
    throw InputError("--set: '" + kv.begin()->first +
                     "' is not an updated parameter (YE11, nu12, d31, epsT33_rel)");
  const pu::MaterialClass cls = a.isotropic
                                    ? pu::MaterialClass::isotropic()
                                    : pu::MaterialClass::transversely_isotropic(preset.material);
  (void)cls.e_form(p0);  // non-physical original → std::invalid_argument → exit 2

  pm::MeshOptions mesh;
  mesh.n_radial = a.n_radial;
  mesh.n_axial = a.n_axial;
  pm::TubeModel tube(geometry, mesh);
  pm::ModalSolver solver(tube);

  pu::UpdateOptions uo;
  uo.cmcm.max_iterations = a.max_iterations;
  uo.cmcm.min_cross = a.min_cross;
  uo.cmcm.cross_modes = a.cross_modes || a.seed_procedure;
  uo.seed_procedure = a.seed_procedure;
  if (a.seed_procedure && a.method == "lm") throw InputError("--seed-procedure is a CMCM procedure: use --method cmcm or both");
  if (!a.history_plot.empty() && a.method == "lm") throw InputError("--history-plot draws the CMCM iterations: use --method cmcm or both");
  uo.capacitance =
      a.capacitance == "fe" ? pu::CapacitanceModel::fe : pu::CapacitanceModel::analytic;

  nlohmann::json out;
  out["method"] = a.method;
  out["model_class"] = pu::to_string(cls.kind());
  out["material"] = preset.name;
  out["original"] = params_json(cls, p0);
  out["measured"] = measured;
  bool converged = false;
  pu::TubeParams updated = p0;
  auto alpha_json = [&](const pu::TubeParams& p) {
    const auto q0 = cls.coordinates(p0), q = cls.coordinates(p);
    return nlohmann::json{{"alpha1", q.c1 / q0.c1 - 1},
                          {"alpha2", q.c2 / q0.c2 - 1},
                          {"alpha3", q.a / pu::a_from_d31(p0.d31, q.c1 + q.c2, p0.eps_t33) - 1}};
  };
  nlohmann::json lm_json;
  if (a.method == "lm" || a.method == "both") {
    pu::LmOptions lo;
    const auto lm = pu::update_lm(tube, solver, cls, p0, mf, lo);
    lm_json = {{"updated", params_json(cls, lm.updated)},
               {"converged", lm.ok()},
               {"status", pu::to_string(lm.status)},
               {"message", lm.message},
               {"iterations", lm.iterations},
               {"evaluations", lm.evaluations},
               {"cost", lm.cost},
               {"residuals", lm.residuals},
               {"model_after",
                {{"resonances_hz", lm.model_resonances_hz},
                 {"antiresonances_hz", lm.model_antiresonances_hz}}},
               {"seconds", lm.seconds}};
    try {
      lm_json["alpha"] = alpha_json(lm.updated);
    } catch (const std::invalid_argument&) {
    }
    if (a.method == "lm") {
      converged = lm.ok();
      updated = lm.updated;
      out["updated"] = lm_json["updated"];
      if (lm_json.contains("alpha")) out["alpha"] = lm_json["alpha"];
      // LM updates all four parameters jointly: one iteration count for both groups.
      out["iterations"] = {
          {"elastic", lm.iterations}, {"piezo", lm.iterations}, {"lm", lm.iterations}};
      out["converged"] = converged;
      out["status"] = pu::to_string(lm.status);
      out["message"] = lm.message;
      out["model_after"] = lm_json["model_after"];
      out["seconds"] = lm.seconds;
    } else {
      out["lm"] = lm_json;
    }
  }
  if (a.method != "lm") {
    const auto r = pu::update_cmcm(tube, solver, cls, p0, mf, uo);
    converged = r.ok();
    updated = r.updated;
    out["updated"] = params_json(cls, r.updated);
    out["alpha"] = {{"alpha1", r.alpha1}, {"alpha2", r.alpha2}, {"alpha3", r.alpha3}};
    out["procedure"] = {{"name", a.seed_procedure ? "seed" : "sweeps"}, {"cross_modes", uo.cmcm.cross_modes}};
    {
      nlohmann::json el = nlohmann::json::array(), pz = nlohmann::json::array();
      for (const auto& h : r.elastic_alpha_history) el.push_back({h[0], h[1]});
      for (double h : r.piezo_alpha_history) pz.push_back(std::isfinite(h) ? nlohmann::json(h) : nlohmann::json());
      out["alpha_history"] = {{"elastic", el}, {"piezo", pz}};
    }
    if (!a.history_plot.empty()) {
      // A plot that cannot be written costs the plot, not the result.
      try {
        write_history_plot(r, a.seed_procedure, a.history_plot);
        out["history_plot"] = a.history_plot;
      } catch (const std::exception& e) {
        out["history_plot_error"] = e.what();
        if (a.warn) a.warn(std::string("--history-plot: ") + e.what() + "; the result is printed without it");
      }
    }
    out["iterations"] = {{"elastic", r.iterations_elastic},
                         {"piezo", r.iterations_piezo},
                         {"elastic_per_sweep", r.elastic_per_sweep},
                         {"piezo_per_sweep", r.piezo_per_sweep},
                         {"sweeps", r.sweeps}};
    out["converged"] = converged;
    out["status"] = pu::to_string(r.status);
    out["message"] = r.message;
    out["eps_t33_eq201_rel"] = r.eps_t33_eq201 / pm::kEps0;
    out["capacitance"] = {
        {"model", a.seed_procedure ? std::string("analytic") : a.capacitance},  // eq. 201 in the seed's procedure
        {"measured_f", r.c_measured},
        {"model_after_f", r.c_model_after}};
    out["model_before"] = {{"resonances_hz", r.model_resonances_before_hz},
                           {"antiresonances_hz", r.model_antiresonances_before_hz}};
    out["model_after"] = {{"resonances_hz", r.model_resonances_hz},
                          {"antiresonances_hz", r.model_antiresonances_hz}};
    out["seconds"] = r.seconds;
    if (a.method == "both" && lm_json.contains("updated")) {
      nlohmann::json diff;
      for (const char* k : {"YE11", "nu12", "d31", "epsT33_rel"})
        diff[k] = lm_json["updated"][k].get<double>() / out["updated"][k].get<double>() - 1.0;
      out["lm_minus_cmcm_relative"] = diff;
    }
  }

  pm::RayleighDamping damping;
  damping.beta = 1e-7;  // seed ch. 5 default for the overlay when no fit is given
  if (!a.damping.empty()) {
    std::vector<std::pair<double, double>> fz;
    std::stringstream ss(a.damping);
    std::string item;
    while (std::getline(ss, item, ',')) {
      const auto c = item.find(':');
      if (c == std::string::npos) throw InputError("--damping: expected F:ZETA,F:ZETA");
      fz.emplace_back(pu::parse_list(item.substr(0, c)).at(0),
                      pu::parse_list(item.substr(c + 1)).at(0));
    }
    if (fz.size() != 2) throw InputError("--damping: exactly two modes F1:ZETA1,F2:ZETA2");
    // The two-parameter fit where physical, else the one-parameter damping
    // the two modes support with its sigma (issue 19: no refusal).
    const auto fit = pu::damping_from_modes(fz[0].first, fz[0].second, fz[1].first, fz[1].second);
    auto num = [](double x) {
      return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr);
    };
    out["rayleigh"] = {{"ok", fit.ok},
                       {"message", fit.ok ? fit.note : fit.message},
                       {"alpha", fit.damping.alpha},
                       {"beta", fit.damping.beta},
                       {"model", fit.model},
                       {"alpha_sigma", num(fit.alpha_sigma)},
                       {"beta_sigma", num(fit.beta_sigma)},
                       {"qm", {num(fit.qm1), num(fit.qm2)}}};
    if (fit.ok)
      damping = fit.damping;
    else if (a.warn)
      a.warn(fit.message);
  }

  if (!a.overlay.empty()) {
    std::vector<double> f;
    if (curve) {
      for (double x : curve->f_hz)
        if (x > 0) f.push_back(x);
    } else {
      f = pm::frequency_grid(100, 1.2 * mf.antiresonances_hz.back(), 100);
    }
    const auto z0 = model_impedance(solver, cls.e_form(p0), f, damping);
    std::vector<std::complex<double>> z1;
    try {
      z1 = model_impedance(solver, cls.e_form(updated), f, damping);
    } catch (const std::invalid_argument&) {
      z1.assign(f.size(), std::complex<double>(NAN, NAN));
    }
    std::ofstream os(a.overlay);
    if (!os) throw InputError("--overlay: cannot write '" + a.overlay + "'");
    os.precision(10);
    os << "f_hz,original_abs_ohm,updated_abs_ohm,measured_abs_ohm,original_phase_deg,"
          "updated_phase_deg,measured_phase_deg\n";
    std::size_t k = 0;
    for (std::size_t i = 0; i < f.size(); ++i) {
      os << f[i] << ',' << std::abs(z0[i]) << ',' << std::abs(z1[i]) << ',';
      std::complex<double> zm(NAN, NAN);
      if (curve) {
        while (k < curve->f_hz.size() && curve->f_hz[k] < f[i]) ++k;
        if (k < curve->f_hz.size() && curve->f_hz[k] == f[i]) zm = curve->z_ohm[k];
      }
      if (std::isfinite(zm.real())) os << std::abs(zm);
      os << ',' << std::arg(z0[i]) * 180 / M_PI << ',' << std::arg(z1[i]) * 180 / M_PI << ',';
      if (std::isfinite(zm.real())) os << std::arg(zm) * 180 / M_PI;
      os << '\n';
    }
    out["overlay"] = {{"file", a.overlay},
                      {"points", f.size()},
                      {"rayleigh_alpha", damping.alpha},
                      {"rayleigh_beta", damping.beta}};
  }

  return {std::move(out), preset.name, converged};
}

}  // namespace piezo::jobs
