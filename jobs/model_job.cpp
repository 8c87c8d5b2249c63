// The jobs' room (jobs/): the FE tube model's commands (see model_job.hpp).
#include "jobs/model_job.hpp"

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "jobs/job_error.hpp"
#include "jobs/report/mode_shapes_plot.hpp"
#include "jobs/report/plot_cairo.hpp"
#include "model/harmonic.hpp"
#include "model/material_presets.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"

namespace piezo::jobs {

namespace {

namespace pm = piezo::model;

// Material (e-form) and density from the preset, the model class and --set.
struct Resolved {
  pm::PiezoMaterialE material;
  std::string model_class;
  nlohmann::json parameters;
};

Resolved resolve(ModelRequest& a) {
  // std::invalid_argument (unknown preset, bad override) → exit 2
  const auto m = pm::resolve_material({a.material, a.isotropic, a.set});
  a.geometry.density_kg_m3 = m.density_kg_m3;
  Resolved r;
  const auto& d = m.d;
  if (a.isotropic) {
    const auto p = pm::isotropic_params(d);
    r.model_class = "isotropic";
    r.parameters = {{"YE11", p.y_e11}, {"nu12", p.nu12}, {"d31", p.d31},
                    {"epsT33_rel", p.eps_t33 / pm::kEps0}};
  } else {
    r.model_class = "full";
    r.parameters = {{"sE11", d.s_e11}, {"sE12", d.s_e12}, {"sE13", d.s_e13},
                    {"sE33", d.s_e33}, {"sE44", d.s_e44}, {"d31", d.d31},
                    {"d33", d.d33},    {"d15", d.d15},    {"epsT11_rel", d.eps_t11 / pm::kEps0},
                    {"epsT33_rel", d.eps_t33 / pm::kEps0}};
  }
  r.material = pm::to_e_form(d);
  r.parameters["rho"] = a.geometry.density_kg_m3;
  return r;
}

nlohmann::json mode_json(const pm::Mode& m, std::size_t index, pm::Electrodes e) {
  return {{"circuit", e == pm::Electrodes::short_circuit ? "short" : "open"},
          {"index", index},
          {"frequency_hz", m.frequency_hz},
          {"symmetry", pm::to_string(m.symmetry)},
          {"symmetric_fraction", m.symmetric_fraction},
          {"coupling", m.coupling},
          {"electrically_active", m.electrically_active}};
}

nlohmann::json tracked_json(const std::vector<pm::TrackedMode>& v) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& t : v)
    a.push_back({{"nominal_hz", t.nominal_hz},
                 {"perturbed_hz", t.perturbed_hz},
                 {"change", t.change},
                 {"mac", t.mac}});
  return a;
}

}  // namespace

ResolvedModel resolve_model(ModelRequest& req) {
  auto r = resolve(req);
  return {r.material, std::move(r.model_class), std::move(r.parameters)};
}

nlohmann::json materials_json() {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& p : pm::material_presets())
    j.push_back({{"name", p.name}, {"description", p.description}, {"density_kg_m3", p.density_kg_m3}});
  return j;
}

ModalJobResult run_modal(ModelRequest a, int modes, const std::string& shapes_plot) {
  const auto r = resolve(a);
  if (modes < 1 || modes > 200) throw InputError("--modes must be in 1..200");
  const std::filesystem::path plot(shapes_plot);
  if (!shapes_plot.empty() && plot.extension() != ".png" && plot.extension() != ".svg")
    throw InputError("--plot-shapes " + shapes_plot + ": give a .png or .svg file name");
  pm::TubeModel tm(a.geometry, {a.n_radial, a.n_axial});
  pm::ModalSolver solver(tm);
  pm::ModalOptions o;
  o.n_modes = modes;
  const auto sc = solver.solve(r.material, pm::Electrodes::short_circuit, o);
  const auto oc = solver.solve(r.material, pm::Electrodes::open_circuit, o);
  nlohmann::json j;
  j["material"] = a.material;
  j["model_class"] = r.model_class;
  j["parameters"] = r.parameters;
  j["mesh"] = {{"n_radial", a.n_radial}, {"n_axial", a.n_axial}, {"n_u", tm.n_u()}};
  j["short_circuit_hz"] = sc.active_frequencies_hz();
  j["open_circuit_hz"] = oc.active_frequencies_hz();
  j["modes"] = nlohmann::json::array();
  for (std::size_t k = 0; k < sc.modes.size(); ++k)
    j["modes"].push_back(mode_json(sc.modes[k], k, pm::Electrodes::short_circuit));
  for (std::size_t k = 0; k < oc.modes.size(); ++k)
    j["modes"].push_back(mode_json(oc.modes[k], k, pm::Electrodes::open_circuit));
  j["c_clamped_f"] = sc.c_clamped;
  j["c_static_f"] = solver.static_capacitance(r.material);
  j["converged"] = sc.converged && oc.converged;
  if (!shapes_plot.empty()) {
    const auto fig = report::mode_shapes_figure(
        tm.mesh(), sc, oc, a.material + " (" + r.model_class + " class), mesh " + std::to_string(a.n_radial) + " x " +
                               std::to_string(a.n_axial) + " nine-node elements");
    if (plot.extension() == ".png")
      report::write_png(fig, plot);
    else
      report::write_svg(fig, plot);
    j["shapes_plot"] = shapes_plot;
  }
  ModalJobResult out;
  out.json = std::move(j);
  out.model_class = r.model_class;
  out.converged = sc.converged && oc.converged;
  if (!out.converged) out.message = sc.converged ? oc.message : sc.message;
  return out;
}

ModelImpedanceResult run_model_impedance(ModelRequest a, const SweepRequest& s) {
  const auto r = resolve(a);
  std::vector<double> f;
  try {
    f = pm::frequency_grid(s.fmin, s.fmax, s.step);
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("--fmin/--fmax/--step: ") + e.what());
  }
  pm::RayleighDamping d{s.alpha, s.beta};
  pm::MaterialLosses l;
  if (s.qm > 0) l.qm = s.qm;
  l.tan_delta = s.tan_delta;
  d.validate();
  l.validate();
  pm::TubeModel tm(a.geometry, {a.n_radial, a.n_axial});
  std::vector<pm::Complex> y;
  if (s.direct) {
    pm::DirectHarmonicSolver ds(tm);
    y = ds.admittance(r.material, f, d, l);
  } else {
    pm::ModalSolver solver(tm);
    pm::ModalOptions o;
    o.n_modes = s.modes;
    const auto port = solver.port_model(r.material, o);
    if (!port.converged) throw std::runtime_error("modal solve did not converge");
    y = pm::admittance_modal(port, f, d, l);
  }
  ModelImpedanceResult out;
  out.model_class = r.model_class;
  out.z_ohm = pm::impedance_from_admittance(y);
  out.f_hz = std::move(f);
  return out;
}

nlohmann::json model_impedance_json(const ModelRequest& a, const SweepRequest& s, const ModelImpedanceResult& r) {
  nlohmann::json j;
  j["material"] = a.material;
  j["model_class"] = r.model_class;
  j["method"] = s.direct ? "direct" : "modal";
  j["f_hz"] = r.f_hz;
  auto& re = j["re_ohm"] = nlohmann::json::array();
  auto& im = j["im_ohm"] = nlohmann::json::array();
  for (const auto& zi : r.z_ohm) {
    re.push_back(std::isfinite(zi.real()) ? nlohmann::json(zi.real()) : nlohmann::json());
    im.push_back(std::isfinite(zi.real()) ? nlohmann::json(zi.imag()) : nlohmann::json());
  }
  return j;
}

SensitivityJobResult run_sensitivity(ModelRequest a, const SensitivityRequest& study) {
  const auto r = resolve(a);
  const auto m = pm::resolve_material({a.material, a.isotropic, a.set});
  const double band_hz = study.band_hz;
  pm::SensitivityOptions o;
  o.band_hz = band_hz;
  o.mesh = {a.n_radial, a.n_axial};
  o.form = study.form;
  o.seed_protocol = study.seed_protocol;
  try {
    o.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  const auto res = pm::form_sensitivity(a.geometry, m.d, o);
  const auto& params = pm::sensitivity_params(o.form);
  nlohmann::json j;
  j["material"] = a.material;
  j["form"] = pm::to_string(o.form);
  j["seed_protocol"] = o.seed_protocol;
  j["model_class"] = r.model_class;
  j["mesh"] = {{"n_radial", a.n_radial}, {"n_axial", a.n_axial}};
  j["band_hz"] = band_hz;
  j["nominal"] = {{"short_circuit_hz", res.nominal.short_hz},
                  {"open_circuit_hz", res.nominal.open_hz},
                  {"c_static_f", res.nominal.c_static_f}};
  j["cases"] = nlohmann::json::array();
  for (const auto& c : res.cases) {
    nlohmann::json cj = {{"param", c.name},
                         {"factor", c.factor},
                         {"seed_says_sensitive", params[static_cast<std::size_t>(c.index)].seed_says_sensitive},
                         {"valid", c.valid},
                         {"physical", c.physical},
                         {"solved", c.solved}};
    if (!c.reason.empty()) cj["reason"] = c.reason;
    if (c.solved) {
      cj["short_circuit"] = tracked_json(c.short_modes);
      cj["open_circuit"] = tracked_json(c.open_modes);
      cj["c_static_change"] = c.c_static_change;
      cj["max_abs_change"] = c.max_abs_change;
      cj["min_mac"] = c.min_mac;
      cj["perturbed_short_circuit_hz"] = c.perturbed.short_hz;
      cj["perturbed_open_circuit_hz"] = c.perturbed.open_hz;
    }
    j["cases"].push_back(std::move(cj));
  }
  j["converged"] = res.converged;
  return {res, r.model_class, std::move(j)};
}

}  // namespace piezo::jobs
