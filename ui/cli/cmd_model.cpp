// `piezobench model …`: the FE tube model from the command line.
//   model materials                      presets and their sources
//   model modal     --material M [--isotropic] [--set k=v,…] [--modes N] [--json]
//   model impedance --material M --fmin HZ --fmax HZ --step HZ [--rayleigh-beta S] [--csv|--json]
// Exit codes: 0 ok, 2 bad input (unknown material, bad --set), 1 non-convergence
// or internal failure.
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "model/harmonic.hpp"
#include "model/material_presets.hpp"
#include "model/modal.hpp"
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

std::map<std::string, double> parse_set(const std::string& s) {
  std::map<std::string, double> kv;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item.empty()) continue;
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError("--set: expected key=value, got '" + item + "'");
    const std::string key = item.substr(0, eq), val = item.substr(eq + 1);
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(val, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != val.size() || !std::isfinite(v))
      throw InputError("--set: bad number for " + key + ": '" + val + "'");
    kv[key] = v;
  }
  return kv;
}

// Material (e-form) and density from the preset, the model class and --set.
struct Resolved {
  pm::PiezoMaterialE material;
  std::string model_class;
  nlohmann::json parameters;
};

Resolved resolve(ModelArgs& a) {
  const auto& preset = pm::find_preset(a.material);  // std::invalid_argument → exit 2
  auto kv = parse_set(a.set);
  if (auto it = kv.find("rho"); it != kv.end()) {
    a.geometry.density_kg_m3 = it->second;
    kv.erase(it);
  } else {
    a.geometry.density_kg_m3 = preset.density_kg_m3;
  }
  Resolved r;
  auto take = [&](const char* key, double& field, double scale = 1.0) {
    if (auto it = kv.find(key); it != kv.end()) {
      field = it->second * scale;
      kv.erase(it);
    }
  };
  if (a.isotropic) {
    auto p = pm::isotropic_params(preset.material);
    take("YE11", p.y_e11);
    take("nu12", p.nu12);
    take("d31", p.d31);
    take("epsT33", p.eps_t33);
    take("epsT33_rel", p.eps_t33, pm::kEps0);
    r.model_class = "isotropic";
    r.parameters = {{"YE11", p.y_e11}, {"nu12", p.nu12}, {"d31", p.d31},
                    {"epsT33_rel", p.eps_t33 / pm::kEps0}};
    if (!kv.empty())
      throw InputError("--set: '" + kv.begin()->first +
                       "' is not a parameter of the isotropic class (YE11, nu12, d31, epsT33_rel, rho)");
    r.material = pm::to_e_form(pm::to_d_form(p));
  } else {
    auto d = preset.material;
    take("sE11", d.s_e11);
    take("sE12", d.s_e12);
    take("sE13", d.s_e13);
    take("sE33", d.s_e33);
    take("sE44", d.s_e44);
    take("d31", d.d31);
    take("d33", d.d33);
    take("d15", d.d15);
    take("epsT11", d.eps_t11);
    take("epsT33", d.eps_t33);
    take("epsT11_rel", d.eps_t11, pm::kEps0);
    take("epsT33_rel", d.eps_t33, pm::kEps0);
    if (!kv.empty())
      throw InputError("--set: unknown d-form parameter '" + kv.begin()->first +
                       "' (sE11 sE12 sE13 sE33 sE44 d31 d33 d15 epsT11[_rel] epsT33[_rel] rho)");
    r.model_class = "full";
    r.parameters = {{"sE11", d.s_e11}, {"sE12", d.s_e12}, {"sE13", d.s_e13},
                    {"sE33", d.s_e33}, {"sE44", d.s_e44}, {"d31", d.d31},
                    {"d33", d.d33},    {"d15", d.d15},    {"epsT11_rel", d.eps_t11 / pm::kEps0},
                    {"epsT33_rel", d.eps_t33 / pm::kEps0}};
    r.material = pm::to_e_form(d);
  }
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
}

}  // namespace piezo::cli
