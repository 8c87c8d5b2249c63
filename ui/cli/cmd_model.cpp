// `piezobench model …`: the FE tube model from the command line.
//   model materials                      presets and their sources
//   model modal     --material M [--isotropic] [--set k=v,…] [--modes N] [--plot-shapes F] [--json]
//   model impedance --material M --fmin HZ --fmax HZ --step HZ [--rayleigh-beta S] [--csv|--json]
//   model sensitivity [--material M] [--band HZ] [--form d|engineering|e] [--seed-protocol] [--json]
//                                                            (Appendix C, model/sensitivity.hpp)
//   model mode-shape-cmcm [--json] …                         (Appendix D, cmd_model_mode_shape.cpp)
//   model three-d | constrained …                            (Table 3 3-D, Figs 17, 19: cmd_model_3d.cpp)
//   model bar [--mode 31|33] [--ends free-free|fixed-mass] … (Appendix A: cmd_model_bar.cpp)
// Exit codes: 0 ok, 2 bad input (unknown material, bad --set), 1 non-convergence
// or internal failure. The CLI's room (ui/cli): options and printing; the
// model work is jobs/model_job.hpp.
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "jobs/model_job.hpp"
#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

namespace {

using jobs::ModelRequest;
using jobs::SweepRequest;

void add_model_options(CLI::App* cmd, ModelRequest& a) {
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

struct SweepArgs {
  SweepRequest sweep;
  bool csv = false;  // the default text form: accepted, changes nothing
};

struct ModalArgs {
  ModelRequest model;
  int modes = 10;
  std::string plot_shapes;
};

void run_modal(Context& ctx, const ModalArgs& args) {
  const ModelRequest& a = args.model;
  const auto r = jobs::run_modal(a, args.modes, args.plot_shapes);
  const auto& j = r.json;
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
  if (!r.converged) {
    std::fprintf(stderr, "piezobench: modal solve did not converge: %s\n", r.message.c_str());
    ctx.exit_code = kInternal;
  }
}

void run_impedance(Context& ctx, const ModelRequest& a, const SweepRequest& s) {
  const auto r = jobs::run_model_impedance(a, s);
  if (ctx.json) {
    print_json(jobs::model_impedance_json(a, s, r));
  } else {  // CSV (the default text form)
    const auto& f = r.f_hz;
    const auto& z = r.z_ohm;
    std::printf("f_hz,re_ohm,im_ohm\n");
    for (std::size_t i = 0; i < f.size(); ++i)
      std::printf("%.10g,%.10g,%.10g\n", f[i], z[i].real(), z[i].imag());
  }
}

std::string percent_list(const std::vector<model::TrackedMode>& v) {
  std::string s;
  char buf[32];
  for (const auto& t : v) {
    std::snprintf(buf, sizeof buf, "%+9.3f", 100 * t.change);
    s += buf;
  }
  return s;
}

void run_sensitivity(Context& ctx, const ModelRequest& a, const jobs::SensitivityRequest& req) {
  const auto study = jobs::run_sensitivity(a, req);
  const auto& res = study.result;
  const auto& params = model::sensitivity_params(req.form);
  const double band_hz = req.band_hz;
  if (ctx.json) {
    print_json(study.json);
  } else {
    std::printf("%s (%s class), mesh %d x %d, active modes below %.0f Hz; each %s-form constant "
                "scaled alone%s\n",
                a.material.c_str(), study.model_class.c_str(), a.n_radial, a.n_axial, band_hz,
                model::to_string(req.form),
                req.seed_protocol ? " by the seed's factor (elastic x2, piezoelectric and dielectric x0.5), "
                                    "non-physical materials solved and flagged (!)"
                                  : "");
    std::printf("nominal: short");
    for (double f : res.nominal.short_hz) std::printf(" %.1f", f);
    std::printf(" Hz | open");
    for (double f : res.nominal.open_hz) std::printf(" %.1f", f);
    std::printf(" Hz | C_static %.5g F\n", res.nominal.c_static_f);
    std::printf("relative change [%%] of each nominal active mode (followed by shape, MAC) and of "
                "C_static; * = sensitive per the seed (%s)\n",
                req.form == model::SensitivityForm::e ? "App. C.2" : "eq 16");
    std::printf("  %-8s %-6s | %-*s | %-*s | %9s | %8s | %5s\n", "param", "factor",
                static_cast<int>(9 * res.nominal.short_hz.size()), "short circuit",
                static_cast<int>(9 * res.nominal.open_hz.size()), "open circuit", "C_static",
                "max", "MAC");
    for (const auto& c : res.cases) {
      std::printf("%c %-8s x%-5g | ", params[static_cast<std::size_t>(c.index)].seed_says_sensitive ? '*' : ' ',
                  c.name.c_str(), c.factor);
      if (!c.solved) {
        std::printf("not physical: %s\n", c.reason.c_str());
        continue;
      }
      std::printf("%s | %s | %+9.3f | %8.3f | %5.3f\n", percent_list(c.short_modes).c_str(),
                  percent_list(c.open_modes).c_str(), 100 * c.c_static_change,
                  100 * c.max_abs_change, c.min_mac);
      if (!c.physical) std::printf("    ! not physical, solved as the seed did: %s\n", c.reason.c_str());
    }
  }
  if (!res.converged) {
    std::fprintf(stderr, "piezobench: modal solve did not converge: %s\n", res.message.c_str());
    ctx.exit_code = kInternal;
  }
}

}  // namespace

void register_model_command(CLI::App& app, Context& ctx) {
  auto* model = app.add_subcommand("model", "FE model of the radially poled tube");
  model->require_subcommand(1);
  add_json_flag(model, ctx);

  auto* mats = model->add_subcommand("materials", "List the material presets");
  add_json_flag(mats, ctx);
  mats->callback([&ctx] {
    ctx.exit_code = run_command(ctx, [&] {
      const nlohmann::json j = jobs::materials_json();
      if (ctx.json)
        print_json(j);
      else
        for (const auto& p : j)
          std::printf("%-8s %s\n", p["name"].get<std::string>().c_str(),
                      p["description"].get<std::string>().c_str());
    });
  });

  auto margs = std::make_shared<ModalArgs>();
  auto* modal = model->add_subcommand("modal", "Short- and open-circuit modal analysis");
  add_model_options(modal, margs->model);
  modal->add_option("--modes", margs->modes, "Number of modes per circuit")->capture_default_str();
  modal->add_option("--plot-shapes", margs->plot_shapes,
                    "Draw the mode shapes (seed Figs 7, 12, 13) as PNG or SVG (by the extension)");
  add_json_flag(modal, ctx);
  modal->callback([&ctx, margs] {
    ctx.exit_code = run_command(ctx, [&] { run_modal(ctx, *margs); });
  });

  auto iargs = std::make_shared<ModelRequest>();
  auto sargs = std::make_shared<SweepArgs>();
  auto* imp = model->add_subcommand("impedance", "Electrical impedance Z(f) of the tube");
  add_model_options(imp, *iargs);
  imp->add_option("--fmin", sargs->sweep.fmin, "First frequency [Hz]")->required();
  imp->add_option("--fmax", sargs->sweep.fmax, "Last frequency [Hz]")->required();
  imp->add_option("--step", sargs->sweep.step, "Frequency step [Hz]")->required();
  imp->add_option("--rayleigh-alpha", sargs->sweep.alpha, "Rayleigh α [1/s]");
  imp->add_option("--rayleigh-beta", sargs->sweep.beta, "Rayleigh β [s] (seed ch. 5: 1e-7)");
  imp->add_option("--qm", sargs->sweep.qm, "Mechanical quality factor (complex stiffness)");
  imp->add_option("--tan-delta", sargs->sweep.tan_delta, "Dielectric loss tangent");
  imp->add_option("--modes", sargs->sweep.modes, "Modes in the superposition")->capture_default_str();
  imp->add_flag("--direct", sargs->sweep.direct, "Direct complex sparse solve (reference, slow)");
  imp->add_flag("--csv", sargs->csv, "CSV output f_hz,re_ohm,im_ohm (default)");
  add_json_flag(imp, ctx);
  imp->callback([&ctx, iargs, sargs] {
    ctx.exit_code = run_command(ctx, [&] { run_impedance(ctx, *iargs, sargs->sweep); });
  });

  auto sens_args = std::make_shared<ModelRequest>();
  auto sreq = std::make_shared<jobs::SensitivityRequest>();
  auto* sens = model->add_subcommand(
      "sensitivity", "Seed Appendix C: each constant doubled and halved (d, engineering or e form)");
  add_model_options(sens, *sens_args);
  sens->add_option("--band", sreq->band_hz, "Upper band edge [Hz] (seed Tables C.1, C.3: 200 kHz)")
      ->capture_default_str();
  const std::map<std::string, model::SensitivityForm> forms = {{"d", model::SensitivityForm::d},
                                                               {"engineering", model::SensitivityForm::engineering},
                                                               {"e", model::SensitivityForm::e}};
  sens->add_option("--form", sreq->form,
                   "Which ten constants: d (Tables C.1, C.3), engineering (YE11 YE33 nu12 nu13 G; C.2), e (C.4, C.5)")
      ->transform(CLI::CheckedTransformer(forms, CLI::ignore_case))
      ->default_str("d");
  sens->add_flag("--seed-protocol", sreq->seed_protocol,
                 "The seed's factors (elastic x2, piezoelectric and dielectric x0.5); a non-physical material "
                 "(sE13 x2, epsT33 x0.5) solved and flagged, as the seed did, instead of refused");
  add_json_flag(sens, ctx);
  sens->callback([&ctx, sens_args, sreq] {
    ctx.exit_code = run_command(ctx, [&] { run_sensitivity(ctx, *sens_args, *sreq); });
  });

  register_mode_shape_command(model, ctx);
  register_model_3d_commands(model, ctx, add_model_options);
  register_model_bar_command(model, ctx);
  register_model_charge_command(model, ctx, add_model_options);
}

}  // namespace piezo::cli
