// `piezobench model …`: the FE tube model from the command line.
//   model materials                      presets and their sources
//   model modal     --material M [--isotropic] [--set k=v,…] [--modes N] [--json]
//   model impedance --material M --fmin HZ --fmax HZ --step HZ [--rayleigh-beta S] [--csv|--json]
//   model sensitivity [--material M] [--band HZ] [--json]   (Appendix C.1, model/sensitivity.hpp)
//   model mode-shape-cmcm [--json] …                         (Appendix D, cmd_model_mode_shape.cpp)
// Exit codes: 0 ok, 2 bad input (unknown material, bad --set), 1 non-convergence
// or internal failure.
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "model/harmonic.hpp"
#include "model/material_presets.hpp"
#include "model/modal.hpp"
#include "model/material_spec.hpp"
#include "model/sensitivity.hpp"
#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

namespace {

namespace pm = piezo::model;

struct ModelArgs {
  std::string material = "apc850";
  bool isotropic = false;
  std::string set;
  int modes = 10;
  int n_radial = pm::MeshOptions{}.n_radial;
  int n_axial = pm::MeshOptions{}.n_axial;
  pm::TubeGeometry geometry;
  bool geometry_given_density = false;
};

// Material (e-form) and density from the preset, the model class and --set.
struct Resolved {
  pm::PiezoMaterialE material;
  std::string model_class;
  nlohmann::json parameters;
};

Resolved resolve(ModelArgs& a) {
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

void add_model_options(CLI::App* cmd, ModelArgs& a) {
  cmd->add_option("--material", a.material, "Material preset (see `model materials`)")
      ->capture_default_str();
  cmd->add_flag("--isotropic", a.isotropic,
                "Isotropic-simplification class of seed §6.4.3 (YE11, nu12, d31, epsT33)");
  cmd->add_option("--set", a.set, "Override parameters: key=value,… (e.g. YE11=6.66e10,nu12=0.3333)");
  cmd->add_option("--nr", a.n_radial, "Elements through the wall")->capture_default_str();
  cmd->add_option("--nz", a.n_axial, "Elements along the length")->capture_default_str();
  cmd->add_option("--inner-diameter", a.geometry.inner_diameter_m, "Di [m]")->capture_default_str();
  cmd->add_option("--outer-diameter", a.geometry.outer_diameter_m, "Do [m]")->capture_default_str();
  cmd->add_option("--length", a.geometry.length_m, "L [m]")->capture_default_str();
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

void run_modal(Context& ctx, ModelArgs a) {
  const auto r = resolve(a);
  if (a.modes < 1 || a.modes > 200) throw InputError("--modes must be in 1..200");
  pm::TubeModel tm(a.geometry, {a.n_radial, a.n_axial});
  pm::ModalSolver solver(tm);
  pm::ModalOptions o;
  o.n_modes = a.modes;
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
  if (ctx.json) {
    print_json(j);
  } else {
    std::printf("%s (%s class), mesh %d x %d, C_static %.5g F\n", a.material.c_str(),
                r.model_class.c_str(), a.n_radial, a.n_axial, j["c_static_f"].get<double>());
    std::printf("  %-6s %3s %14s  %-13s %10s  %s\n", "circuit", "#", "f [Hz]", "symmetry",
                "coupling", "active");
    for (const auto& m : j["modes"])
      std::printf("  %-6s %3zu %14.2f  %-13s %10.3e  %s\n",
                  m["circuit"].get<std::string>().c_str(), m["index"].get<std::size_t>(),
                  m["frequency_hz"].get<double>(), m["symmetry"].get<std::string>().c_str(),
                  m["coupling"].get<double>(), m["electrically_active"].get<bool>() ? "yes" : "");
  }
  if (!(sc.converged && oc.converged)) {
    std::fprintf(stderr, "piezobench: modal solve did not converge: %s\n",
                 (sc.converged ? oc.message : sc.message).c_str());
    ctx.exit_code = kInternal;
  }
}

struct SweepArgs {
  double fmin = 0, fmax = 0, step = 0, alpha = 0, beta = 0;
  double qm = 0, tan_delta = 0;
  bool csv = false, direct = false;
  int modes = 20;
};

void run_impedance(Context& ctx, ModelArgs a, const SweepArgs& s) {
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
  const auto z = pm::impedance_from_admittance(y);
  if (ctx.json) {
    nlohmann::json j;
    j["material"] = a.material;
    j["model_class"] = r.model_class;
    j["method"] = s.direct ? "direct" : "modal";
    j["f_hz"] = f;
    auto& re = j["re_ohm"] = nlohmann::json::array();
    auto& im = j["im_ohm"] = nlohmann::json::array();
    for (const auto& zi : z) {
      re.push_back(std::isfinite(zi.real()) ? nlohmann::json(zi.real()) : nlohmann::json());
      im.push_back(std::isfinite(zi.real()) ? nlohmann::json(zi.imag()) : nlohmann::json());
    }
    print_json(j);
  } else {  // CSV (the default text form)
    std::printf("f_hz,re_ohm,im_ohm\n");
    for (std::size_t i = 0; i < f.size(); ++i)
      std::printf("%.10g,%.10g,%.10g\n", f[i], z[i].real(), z[i].imag());
  }
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

std::string percent_list(const std::vector<pm::TrackedMode>& v) {
  std::string s;
  char buf[32];
  for (const auto& t : v) {
    std::snprintf(buf, sizeof buf, "%+9.3f", 100 * t.change);
    s += buf;
  }
  return s;
}

void run_sensitivity(Context& ctx, ModelArgs a, double band_hz) {
  const auto r = resolve(a);
  const auto m = pm::resolve_material({a.material, a.isotropic, a.set});
  pm::SensitivityOptions o;
  o.band_hz = band_hz;
  o.mesh = {a.n_radial, a.n_axial};
  try {
    o.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  const auto res = pm::d_form_sensitivity(a.geometry, m.d, o);
  nlohmann::json j;
  j["material"] = a.material;
  j["model_class"] = r.model_class;
  j["mesh"] = {{"n_radial", a.n_radial}, {"n_axial", a.n_axial}};
  j["band_hz"] = band_hz;
  j["nominal"] = {{"short_circuit_hz", res.nominal.short_hz},
                  {"open_circuit_hz", res.nominal.open_hz},
                  {"c_static_f", res.nominal.c_static_f}};
  j["cases"] = nlohmann::json::array();
  for (const auto& c : res.cases) {
    nlohmann::json cj = {{"param", pm::d_param_name(c.param)},
                         {"factor", c.factor},
                         {"seed_says_sensitive", pm::seed_says_sensitive(c.param)},
                         {"valid", c.valid}};
    if (!c.valid) {
      cj["reason"] = c.reason;
    } else {
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
  if (ctx.json) {
    print_json(j);
  } else {
    std::printf("%s (%s class), mesh %d x %d, active modes below %.0f Hz; each d-form constant "
                "scaled alone\n",
                a.material.c_str(), r.model_class.c_str(), a.n_radial, a.n_axial, band_hz);
    std::printf("nominal: short");
    for (double f : res.nominal.short_hz) std::printf(" %.1f", f);
    std::printf(" Hz | open");
    for (double f : res.nominal.open_hz) std::printf(" %.1f", f);
    std::printf(" Hz | C_static %.5g F\n", res.nominal.c_static_f);
    std::printf("relative change [%%] of each nominal active mode (followed by shape, MAC) and of "
                "C_static; * = sensitive per seed eq 16\n");
    std::printf("  %-8s %-6s | %-*s | %-*s | %9s | %8s | %5s\n", "param", "factor",
                static_cast<int>(9 * res.nominal.short_hz.size()), "short circuit",
                static_cast<int>(9 * res.nominal.open_hz.size()), "open circuit", "C_static",
                "max", "MAC");
    for (const auto& c : res.cases) {
      std::printf("%c %-8s x%-5g | ", pm::seed_says_sensitive(c.param) ? '*' : ' ',
                  pm::d_param_name(c.param), c.factor);
      if (!c.valid) {
        std::printf("not physical: %s\n", c.reason.c_str());
        continue;
      }
      std::printf("%s | %s | %+9.3f | %8.3f | %5.3f\n", percent_list(c.short_modes).c_str(),
                  percent_list(c.open_modes).c_str(), 100 * c.c_static_change,
                  100 * c.max_abs_change, c.min_mac);
    }
  }
  if (!res.converged) {
    std::fprintf(stderr, "piezobench: modal solve did not converge: %s\n", res.message.c_str());
    ctx.exit_code = kInternal;
  }
}

}  // namespace

void register_model_commands(CLI::App& app, Context& ctx) {
  auto* model = app.add_subcommand("model", "FE model of the radially poled tube");
  model->require_subcommand(1);
  add_json_flag(model, ctx);

  auto* mats = model->add_subcommand("materials", "List the material presets");
  add_json_flag(mats, ctx);
  mats->callback([&ctx] {
    ctx.exit_code = run_command(ctx, [&] {
      nlohmann::json j = nlohmann::json::array();
      for (const auto& p : pm::material_presets())
        j.push_back({{"name", p.name}, {"description", p.description}, {"density_kg_m3", p.density_kg_m3}});
      if (ctx.json)
        print_json(j);
      else
        for (const auto& p : j)
          std::printf("%-8s %s\n", p["name"].get<std::string>().c_str(),
                      p["description"].get<std::string>().c_str());
    });
  });

  auto margs = std::make_shared<ModelArgs>();
  auto* modal = model->add_subcommand("modal", "Short- and open-circuit modal analysis");
  add_model_options(modal, *margs);
  modal->add_option("--modes", margs->modes, "Number of modes per circuit")->capture_default_str();
  add_json_flag(modal, ctx);
  modal->callback([&ctx, margs] {
    ctx.exit_code = run_command(ctx, [&] { run_modal(ctx, *margs); });
  });

  auto iargs = std::make_shared<ModelArgs>();
  auto sargs = std::make_shared<SweepArgs>();
  auto* imp = model->add_subcommand("impedance", "Electrical impedance Z(f) of the tube");
  add_model_options(imp, *iargs);
  imp->add_option("--fmin", sargs->fmin, "First frequency [Hz]")->required();
  imp->add_option("--fmax", sargs->fmax, "Last frequency [Hz]")->required();
  imp->add_option("--step", sargs->step, "Frequency step [Hz]")->required();
  imp->add_option("--rayleigh-alpha", sargs->alpha, "Rayleigh α [1/s]");
  imp->add_option("--rayleigh-beta", sargs->beta, "Rayleigh β [s] (seed ch. 5: 1e-7)");
  imp->add_option("--qm", sargs->qm, "Mechanical quality factor (complex stiffness)");
  imp->add_option("--tan-delta", sargs->tan_delta, "Dielectric loss tangent");
  imp->add_option("--modes", sargs->modes, "Modes in the superposition")->capture_default_str();
  imp->add_flag("--direct", sargs->direct, "Direct complex sparse solve (reference, slow)");
  imp->add_flag("--csv", sargs->csv, "CSV output f_hz,re_ohm,im_ohm (default)");
  add_json_flag(imp, ctx);
  imp->callback([&ctx, iargs, sargs] {
    ctx.exit_code = run_command(ctx, [&] { run_impedance(ctx, *iargs, *sargs); });
  });

  auto sens_args = std::make_shared<ModelArgs>();
  auto band = std::make_shared<double>(pm::SensitivityOptions{}.band_hz);
  auto* sens = model->add_subcommand(
      "sensitivity", "Seed Appendix C.1: each d-form constant doubled and halved");
  add_model_options(sens, *sens_args);
  sens->add_option("--band", *band, "Upper band edge [Hz] (seed Tables C.1, C.3: 200 kHz)")
      ->capture_default_str();
  add_json_flag(sens, ctx);
  sens->callback([&ctx, sens_args, band] {
    ctx.exit_code = run_command(ctx, [&] { run_sensitivity(ctx, *sens_args, *band); });
  });

  register_mode_shape_command(model, ctx);
}

}  // namespace piezo::cli
