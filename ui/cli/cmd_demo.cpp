// `piezobench demo`: the main job end to end on the embedded simulated bench —
// the seed's lab measurement (R1 = 3140 Ω, 1 V exp_decay at 3000 1/s, 20000
// samples at 10 MS/s) of a simulated tube, then every later stage that has
// landed (the same pipeline as the GUI's "Measure and update"). The CLI's
// room (ui/cli): the demo's request and run are jobs/demo_job.hpp.
#include <atomic>
#include <cmath>
#include <cstdio>
#include <iostream>

#include "jobs/demo_job.hpp"
#include "jobs/json/mode_figures_json.hpp"
#include "jobs/export/report_export.hpp"
#include "jobs/text/uncertain_text.hpp"
#include "jobs/text/user_message.hpp"
#include "ui/cli/cli_common.hpp"
#include "ui/cli/diagnosis_text.hpp"

namespace piezo::cli {

void register_demo_command(CLI::App& app, Context& ctx) {
  auto* demo = app.add_subcommand("demo", "Run the main job on the embedded simulated bench");
  auto a = std::make_shared<jobs::DemoRequest>();
  demo->add_option("--out", a->out_dir, "Folder for the demo's files")->capture_default_str();
  demo->add_option("--noise", a->noise, "White noise per channel, std(noise)/std(signal)")->capture_default_str();
  demo->add_option("--seed", a->seed, "Noise seed")->capture_default_str();
  demo->add_option("--effect", a->effects, "Bench effect the simulated bench adds and the model lacks, NAME=VALUE (repeatable)");
  demo->add_option(
      "--disturbance", a->disturbances,
      "A real bench's slow disturbances on the simulated bench: offset=V,offset_shot=V,hum=V[,mains=50|60],"
      "pink=PCT,drift=PCT,step=PCT@SHOT,jitter=SAMPLES (any subset; acquisition/README.md)");
  demo->add_flag("--no-diagnose", a->no_diagnose, "Stop after the update");
  demo->add_option("--calibrate", a->calibrate,
                   "Fixture standards measured before the transducer (open,short,load; load 1000 ohm)")
      ->capture_default_str();
  demo->add_flag("--no-calibrate", a->no_calibrate, "No fixture standards (Cp and R1 error are then aliases)");
  demo->add_option("--shots", a->shots,
                   "Shots of the drive and of the held-out chirp (1 or 2: the one-shot path, the "
                   "gap diagnosed in the output-error model as for most recorded captures)")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  add_json_flag(demo, ctx);
  demo->callback([&ctx, a] {
    ctx.exit_code = run_command(ctx, [&] {
      std::atomic<bool> cancel{false};
      ProgressBar bar("demo");
      auto res = jobs::run_demo(*a, [&](const jobs::PipelineProgress& p) { bar.update(p.fraction, p.stage); }, cancel);
      bar.finish();
      const nlohmann::json j = jobs::report_json(res);  // the same report as replay and the GUI export
      if (ctx.json) {
        print_json(j);
        return;
      }
      std::cout << "piezobench demo — the main job on the embedded simulated bench\n";
      for (const auto& s : res.stages)
        std::cout << "  " << (s.ran ? "[ran]     " : "[skipped] ") << s.name << ": " << jobs::user_message(s.note)
                  << "\n";
      if (!res.params.empty()) {
        // The pipeline's update (output-error: value, sigma, status) beside
        // the seed's extended CMCM and least squares on the same features.
        std::printf("\n  update used: %s\n", res.update_method.c_str());
        std::printf("  %-11s %11s %11s | %-26s %7s %8s %-16s | %11s %8s | %11s %8s\n", "parameter", "original",
                    "true (sim)", "oe ± sigma", "sigma%", "error%", "oe status", "cmcm", "error%", "lm", "error%");
        auto err = [](const std::optional<double>& v, const std::optional<double>& t, char* buf, std::size_t n) {
          if (v && t) std::snprintf(buf, n, "%+.3f", 100.0 * (*v - *t) / *t);
          else std::snprintf(buf, n, "-");
        };
        auto val = [](const std::optional<double>& v, char* buf, std::size_t n) {
          if (v) std::snprintf(buf, n, "%.6g", *v);
          else std::snprintf(buf, n, "-");
        };
        for (const auto& p : res.params) {
          char t[32], os[32] = "-", oee[32], cm[32], cme[32], lm[32], lme[32];
          val(p.truth, t, sizeof t);
          // σ to two significant digits, the value to match; "—" for a σ that is not finite.
          const std::string oe =
              p.oe ? jobs::format_uncertain(*p.oe, p.oe_sigma.value_or(NAN), {}, {true}) : std::string("-");
          const double rel = p.oe ? 100.0 * p.oe_sigma.value_or(NAN) / std::abs(*p.oe) : NAN;
          if (p.oe) std::snprintf(os, sizeof os, "%s", std::isfinite(rel) ? jobs::format_value(rel, {}, 2).c_str() : "—");
          err(p.oe, p.truth, oee, sizeof oee);
          val(p.cmcm, cm, sizeof cm);
          err(p.cmcm, p.truth, cme, sizeof cme);
          val(p.lm, lm, sizeof lm);
          err(p.lm, p.truth, lme, sizeof lme);
          std::printf("  %-11s %11.6g %11s | %-26s %7s %8s %-16s | %11s %8s | %11s %8s\n", p.name.c_str(),
                      p.original, t, oe.c_str(), os, oee, p.oe_status.c_str(), cm, cme, lm, lme);
        }
        if (res.output_error)
          std::printf("  corr(nu12, d31) of the output-error fit: %s; fitted %s\n",
                      std::isfinite(res.output_error->corr_nu12_d31)
                          ? jobs::format_value(res.output_error->corr_nu12_d31, {}, 3).c_str()
                          : "— (not identifiable)",
                      update::damping_summary(*res.output_error).c_str());
      }
      // The per-mode figures (issue 34): the updated model's modes with sigma
      // (or the estimate's BVD fits when the output-error fit did not converge).
      if (j.contains("modes") && !j["modes"].empty()) {
        std::cout << "\n";
        std::fflush(stdout);
        jobs::print_mode_figures(stdout, j["modes"], j["mode_summary"]);
        std::fflush(stdout);
      }
      if (res.diagnosis) print_diagnosis(std::cout, *res.diagnosis);
      print_corrected(std::cout, res);
      if (!res.damping_from_resonances.empty())
        std::cout << "  damping from the resonances: " << res.damping_from_resonances << "\n";
      for (const auto& w : res.warnings) std::cout << "  warning: " << jobs::user_message(w) << "\n";
      std::cout << "\n  capture: " << res.capture_path << " (inspect: piezobench capture info " << res.capture_path
                << ")\n";
    });
  });
}

}  // namespace piezo::cli
