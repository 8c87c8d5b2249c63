// `piezobench diagnose FIT.h5 [--holdout OTHER.h5] --material NAME [--isotropic|--transverse]
//      [--json] [--plot OUT.png] [--plot-size WxH] [--candidates a,b,...]`
// Issue 7: the sim-to-real gap of a recorded capture. Replays FIT.h5 through
// the pipeline (estimate Z, update the model with CMCM) and diagnoses what the
// updated model still misses — where in frequency, of what kind, which effect
// of the catalogue explains it — judged on OTHER.h5 (another capture of the
// same transducer, e.g. a chirp) or, without it, on other shots of FIT.h5.
// Exit codes: 0 diagnosed (whatever the verdict); 2 bad input: a missing or
// invalid file, too few dut shots, a diagnosis that could not run (each named
// with its file); 1 internal failure. The CLI's room (ui/cli): the checks,
// the pipeline and the plot are jobs/diagnose_job.hpp.
#include <cmath>
#include <cstdio>
#include <iostream>

#include "jobs/diagnose_job.hpp"
#include "jobs/text/user_message.hpp"
#include "ui/cli/cli_common.hpp"
#include "jobs/text/uncertain_text.hpp"
#include "ui/cli/diagnosis_text.hpp"

namespace piezo::cli {

namespace {

struct DiagnoseArgs {
  jobs::DiagnoseRequest req;
  bool isotropic = false;  // the default class; excludes --transverse
};

void run_diagnose(Context& ctx, const DiagnoseArgs& args) {
  jobs::DiagnoseRequest req = args.req;
  const jobs::DiagnoseRequest& a = req;
  req.warn = [&](const std::string& w) {
    std::fprintf(stderr, "piezobench: diagnose: %s: %s\n", a.fit.c_str(), jobs::user_message(w).c_str());
  };
  jobs::DiagnoseResult r;
  {
    ProgressBar bar("diagnose");
    req.progress = [&](const jobs::PipelineProgress& p) { bar.update(p.fraction, p.stage); };
    r = jobs::run_diagnose(req);
  }
  const std::string& material = r.material;
  const auto& res = r.pipeline;
  const auto& d = *res.diagnosis;
  const std::string& plot = r.plot;

  if (ctx.json) {
    print_json(jobs::diagnose_json(a, r));
    return;
  }
  std::cout << "piezobench diagnose " << a.fit
            << (a.holdout.empty() ? "" : " --holdout " + a.holdout) << " (" << material << ", "
            << (a.transverse ? "transversely isotropic" : "isotropic") << " class)\n";
  for (const auto& s : res.stages)
    std::cout << "  " << (s.ran ? "[ran]     " : "[skipped] ") << s.name << ": " << s.note << "\n";
  if (!res.params.empty()) {  // the update's constants with sigma (the corrected ones below, when named)
    std::printf("\n  %-12s %14s   %-28s %s\n", "parameter", "original", "updated ± sigma", "status");
    for (const auto& p : res.params) {
      const double v = p.uncorrected ? *p.uncorrected : p.updated;
      const auto s = p.uncorrected ? p.uncorrected_sigma : p.sigma;
      std::printf("  %-12s %14.6g   %-28s %s\n", p.name.c_str(), p.original,
                  jobs::format_uncertain(v, s.value_or(NAN), {}, {true}).c_str(),
                  (p.uncorrected ? p.uncorrected_status : p.status).c_str());
    }
  }
  print_diagnosis(std::cout, d);
  print_corrected(std::cout, res);
  for (const auto& w : res.warnings) std::cout << "  warning: " << w << "\n";
  if (!plot.empty()) std::cout << "\n  plot: " << plot << "\n";
}

}  // namespace

void register_diagnose_command(CLI::App& app, Context& ctx) {
  auto* c = app.add_subcommand(
      "diagnose",
      "Diagnose the sim-to-real gap of a capture: where, what kind, which unmodelled effect");
  auto a = std::make_shared<DiagnoseArgs>();
  c->add_option("FIT", a->req.fit, "Capture to update the model with and diagnose (.h5)")->required();
  c->add_option(
      "--holdout", a->req.holdout,
      "Held-out capture of the same transducer (e.g. a chirp); default: other shots of FIT");
  c->add_option("--material", a->req.material,
                "Nominal material preset (default: the capture's /setup/material)");
  auto* iso = c->add_flag("--isotropic", a->isotropic, "The seed's isotropic class (the default)");
  auto* tr = c->add_flag("--transverse", a->req.transverse, "Transversely isotropic class instead");
  iso->excludes(tr);
  c->add_option("--plot", a->req.plot,
                "Write a PNG: |Z| measured vs model before/after, residual, regions");
  c->add_option("--plot-size", a->req.plot_size, "PNG size WIDTHxHEIGHT")->capture_default_str();
  c->add_option("--candidates", a->req.candidates,
                "Effects to try, comma-separated (default: all supported)")
      ->delimiter(',');
  c->add_flag("--seed-chain", a->req.seed_chain,
              "Also run the seed's chain (Prony features -> extended CMCM, LM where it fails) beside the "
              "output-error fit; its constants go into parameters[].cmcm (default: only when that fit fails)");
  add_chain_tolerance_options(c, a->req.oe);
  add_json_flag(c, ctx);
  c->callback([&ctx, a] { ctx.exit_code = run_command(ctx, [&] { run_diagnose(ctx, *a); }); });
}

}  // namespace piezo::cli
