// `piezobench update [Z.csv | Z.s1p] [--resonances F,… --antiresonances F,… --low-z OHM@HZ]
//      [--material M] [--isotropic] [--set YE11=…,nu12=…,d31=…,epsT33_rel=…]
//      [--method cmcm|lm|both] [--overlay FILE.csv] [--damping F:ZETA,F:ZETA]
//      [--cross-modes] [--seed-procedure] [--history-plot FILE.png|.svg] [--json]`
// Multi-physics FE model updating of the tube (seed §6.3-6.4, docs/update-methods.md).
// Explicit features override the ones found in the file. The CLI's room
// (ui/cli): the work is jobs/update_features_job.hpp and, for a capture,
// jobs/update_capture_job.hpp.
// Exit codes: 0 converged, 2 bad input, 1 not converged / internal failure
// (the JSON result is still printed, with "converged": false and a message).
#include <cstdio>
#include <string>

#include "jobs/update_features_job.hpp"
#include "jobs/text/user_message.hpp"
#include "ui/cli/cli_common.hpp"
#include "ui/cli/cmd_update_capture.hpp"

namespace piezo::cli {

namespace {

struct UpdateArgs {
  jobs::UpdateFeaturesRequest f;  // file, features, method, material, … (method empty: the default of the kind)
  bool transverse = false;
  update::OeOptions oe;  // a capture's output-error fit (the chain's tolerances)
};

void run_update_features(Context& ctx, const UpdateArgs& a0, const std::string& method);

void run_update(Context& ctx, const UpdateArgs& a) {
  if (a.f.file.size() > 3 && a.f.file.compare(a.f.file.size() - 3, 3, ".h5") == 0) {
    // A capture: the tube's constants from the recorded samples.
    if (a.f.isotropic && a.transverse) throw InputError("--isotropic and --transverse exclude each other");
    run_update_capture(ctx, a.f.file, a.f.method.empty() ? "oe" : a.f.method, a.f.material, !a.transverse, a.oe);
    return;
  }
  if (a.transverse) throw InputError("--transverse is for a capture (an impedance file's default class is transversely isotropic)");
  run_update_features(ctx, a, a.f.method.empty() ? "cmcm" : a.f.method);
}

void run_update_features(Context& ctx, const UpdateArgs& a0, const std::string& method) {
  jobs::UpdateFeaturesRequest a = a0.f;
  a.method = method;
  a.warn = [](const std::string& w) { std::fprintf(stderr, "piezobench: %s\n", jobs::user_message(w).c_str()); };
  auto r = jobs::run_update_features(a);
  nlohmann::json& out = r.json;
  const bool converged = r.converged;
  const auto& preset_name = r.material;

  if (ctx.json) {
    print_json(out);
  } else {
    const auto& o = out["original"];
    const auto& u = out["updated"];
    std::printf("model updating (%s, %s class, material %s): %s\n", a.method.c_str(),
                out["model_class"].get<std::string>().c_str(), preset_name.c_str(),
                converged ? "converged" : "NOT converged");
    if (out.contains("message") && !out["message"].get<std::string>().empty())
      std::printf("  %s\n", out["message"].get<std::string>().c_str());
    std::printf("  %-11s %14s %14s\n", "", "original", "updated");
    for (const char* k : {"YE11", "nu12", "d31", "epsT33_rel", "cE11", "cE12", "e31", "epsS33_rel"})
      if (o.contains(k) && u.contains(k))
        std::printf("  %-11s %14.6g %14.6g\n", k, o[k].get<double>(), u[k].get<double>());
    if (out.contains("alpha"))
      std::printf("  alpha1 %.5f  alpha2 %.5f  alpha3 %.5f\n", out["alpha"]["alpha1"].get<double>(),
                  out["alpha"]["alpha2"].get<double>(), out["alpha"]["alpha3"].get<double>());
    std::printf("  iterations: elastic %d, piezo %d%s\n", out["iterations"]["elastic"].get<int>(),
                out["iterations"]["piezo"].get<int>(),
                out.contains("procedure") && out["procedure"]["name"] == "seed" ? " (the seed's procedure)" : "");
    if (out.contains("lm"))
      std::printf("  LM: YE11 %.6g nu12 %.6g d31 %.6g epsT33_rel %.6g (%s)\n",
                  out["lm"]["updated"]["YE11"].get<double>(),
                  out["lm"]["updated"]["nu12"].get<double>(),
                  out["lm"]["updated"]["d31"].get<double>(),
                  out["lm"]["updated"]["epsT33_rel"].get<double>(),
                  out["lm"]["status"].get<std::string>().c_str());
  }
  if (!converged) ctx.exit_code = kInternal;
}

}  // namespace

void register_update_command(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<UpdateArgs>();
  auto* cmd =
      app.add_subcommand("update", "FE model updating: from a capture (output-error fit) or impedance features (extended CMCM, LM)");
  cmd->add_option("FILE", a->f.file,
                  "Impedance file (CSV f_hz,re_ohm,im_ohm or Touchstone .s1p) or a capture (.h5)");
  cmd->add_option("--resonances", a->f.resonances, "Resonances F1,F2,… [Hz]");
  cmd->add_option("--antiresonances", a->f.antiresonances, "Anti-resonances F1,F2,… [Hz]");
  cmd->add_option("--low-z", a->f.low_z, "|Z| at a low frequency, OHM@HZ (e.g. 26804@400)");
  cmd->add_option("--material", a->f.material,
                  "Material preset of the original model (default: a capture's /setup/material, else apc850)");
  cmd->add_flag("--isotropic", a->f.isotropic,
                "Isotropic-simplification class (seed §6.4.3; a capture's default)");
  cmd->add_option("--set", a->f.set, "Original parameters: YE11=…,nu12=…,d31=…,epsT33_rel=…");
  cmd->add_option("--method", a->f.method,
                  "impedance file: cmcm (default), lm or both; capture: oe (default, output-error fit of "
                  "the samples), cmcm, lm or all");
  cmd->add_flag("--transverse", a->transverse,
                "Capture: transversely isotropic class instead of the isotropic one");
  cmd->add_option("--overlay", a->f.overlay, "Write |Z| of original, updated and measured to CSV");
  cmd->add_option("--damping", a->f.damping, "Rayleigh fit from two modes: F1:ZETA1,F2:ZETA2");
  cmd->add_option("--capacitance", a->f.capacitance,
                  "fe (FE capacitance at f_L) or analytic (eq. 201)")
      ->capture_default_str();
  cmd->add_option("--max-iterations", a->f.max_iterations, "CMCM iteration cap per phase")
      ->capture_default_str();
  cmd->add_option("--min-cross", a->f.min_cross,
                  "i != j CMCM pairs with |Phi_i' M Phi*_j| below this share of their norms are left out")
      ->capture_default_str();
  cmd->add_flag("--cross-modes", a->f.cross_modes,
                "Include the i != j CMCM equations (seed-faithful, slow)");
  cmd->add_flag("--seed-procedure", a->f.seed_procedure,
                "The seed's own CMCM procedure (section 7.1.1): one pass, elastic then eq. 201 then piezo, "
                "i != j equations on (Tables 4/5, Figs 36-37)");
  cmd->add_option("--history-plot", a->f.history_plot,
                  "Figs 36-37: the correction coefficients per CMCM iteration, PNG or SVG");
  cmd->add_option("--nr", a->f.n_radial, "Elements through the wall")->capture_default_str();
  cmd->add_option("--nz", a->f.n_axial, "Elements along the length")->capture_default_str();
  add_chain_tolerance_options(cmd, a->oe);
  add_json_flag(cmd, ctx);
  cmd->callback([&ctx, a] { ctx.exit_code = run_command(ctx, [&] { run_update(ctx, *a); }); });
}

}  // namespace piezo::cli
