// `piezobench demo`: the main job end to end on the embedded simulated bench —
// the seed's lab measurement (R1 = 3140 Ω, 1 V exp_decay at 3000 1/s, 20000
// samples at 10 MS/s) of a simulated tube, then every later stage that has
// landed (the same pipeline as the GUI's "Measure and update").
#include <filesystem>
#include <iostream>

#include "acquisition/calibration_plan.hpp"
#include "ui/cli/cli_common.hpp"
#include "model/effects.hpp"
#include "ui/cli/diagnosis_text.hpp"
#include "ui/pipeline.hpp"
#include "ui/report_export.hpp"

namespace piezo::cli {

void register_demo_command(CLI::App& app, Context& ctx) {
  auto* demo = app.add_subcommand("demo", "Run the main job on the embedded simulated bench");
  struct Args {
    std::string out_dir = "demo-out";
    double noise = 0.005;
    std::uint64_t seed = 2016;
    std::vector<std::string> effects;
    bool no_diagnose = false;
    std::string calibrate = "open,short,load";
    bool no_calibrate = false;
    int shots = 16;
  };
  auto a = std::make_shared<Args>();
  demo->add_option("--out", a->out_dir, "Folder for the demo's files")->capture_default_str();
  demo->add_option("--noise", a->noise, "White noise per channel, std(noise)/std(signal)")->capture_default_str();
  demo->add_option("--seed", a->seed, "Noise seed")->capture_default_str();
  demo->add_option("--effect", a->effects, "Bench effect the simulated bench adds and the model lacks, NAME=VALUE (repeatable)");
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
      namespace fs = std::filesystem;
      fs::create_directories(a->out_dir);
      ui::PipelineRequest req;
      req.instrument = "sim";
      req.plan.setup.divider_r1_ohm = 3140.0;
      req.plan.setup.transducer_id = "demo-tube";
      req.plan.setup.material = "apc850";
      req.plan.samples = 20000;
      req.plan.pretrigger_samples = 200;
      req.plan.shots = a->shots;
      // The simulated "real" tube: the seed's Table 4/5 target material in the isotropic class.
      req.sim.material = "apc850";
      req.sim.isotropic = true;
      req.sim.set = "YE11=6.66e10,nu12=0.3333,d31=-210e-12,epsT33_rel=2294";
      req.sim.noise_rel = a->noise;
      req.sim.seed = a->seed;
      for (const auto& e : a->effects) model::apply_effect_assignment(req.sim.effects, e);
      req.diagnose = !a->no_diagnose;
      if (!a->no_calibrate && !a->calibrate.empty())
        req.calibration = acq::parse_calibration_list(a->calibrate, 1000.0);
      // Held-out data for the gap diagnosis: a chirp of the same tube, 1-150 kHz.
      acq::MeasurementPlan ho = req.plan;
      ho.excitation.kind = acq::Excitation::Chirp;
      ho.excitation.f_start_hz = 1e3;
      ho.excitation.f_stop_hz = 150e3;
      ho.excitation.burst_fraction = 0.6;
      req.heldout_plan = ho;
      req.capture_out = (fs::path(a->out_dir) / "demo-capture.h5").string();
      req.material = "apc850";
      req.isotropic = true;
      req.compare_lm = true;  // the table shows oe, cmcm and lm
      std::atomic<bool> cancel{false};
      ProgressBar bar("demo");
      auto res = ui::run_pipeline(req, [&](const ui::PipelineProgress& p) { bar.update(p.fraction, p.stage); }, cancel);
      bar.finish();
      const nlohmann::json j = ui::report_json(res);  // the same report as replay and the GUI export
      if (ctx.json) {
        print_json(j);
        return;
      }
      std::cout << "piezobench demo — the main job on the embedded simulated bench\n";
      for (const auto& s : res.stages)
        std::cout << "  " << (s.ran ? "[ran]     " : "[skipped] ") << s.name << ": " << s.note << "\n";
      if (!res.params.empty()) {
        // The pipeline's update (output-error: value, sigma, status) beside
        // the seed's extended CMCM and least squares on the same features.
        std::printf("\n  update used: %s\n", res.update_method.c_str());
        std::printf("  %-11s %11s %11s | %11s %7s %8s %-16s | %11s %8s | %11s %8s\n", "parameter", "original",
                    "true (sim)", "oe", "sigma%", "error%", "oe status", "cmcm", "error%", "lm", "error%");
        auto err = [](const std::optional<double>& v, const std::optional<double>& t, char* buf, std::size_t n) {
          if (v && t) std::snprintf(buf, n, "%+.3f", 100.0 * (*v - *t) / *t);
          else std::snprintf(buf, n, "-");
        };
        auto val = [](const std::optional<double>& v, char* buf, std::size_t n) {
          if (v) std::snprintf(buf, n, "%.6g", *v);
          else std::snprintf(buf, n, "-");
        };
        for (const auto& p : res.params) {
          char t[32], oe[32], os[32] = "-", oee[32], cm[32], cme[32], lm[32], lme[32];
          val(p.truth, t, sizeof t);
          val(p.oe, oe, sizeof oe);
          if (p.oe) std::snprintf(os, sizeof os, "%.3f", 100.0 * p.oe_sigma.value_or(NAN) / std::abs(*p.oe));
          err(p.oe, p.truth, oee, sizeof oee);
          val(p.cmcm, cm, sizeof cm);
          err(p.cmcm, p.truth, cme, sizeof cme);
          val(p.lm, lm, sizeof lm);
          err(p.lm, p.truth, lme, sizeof lme);
          std::printf("  %-11s %11.6g %11s | %11s %7s %8s %-16s | %11s %8s | %11s %8s\n", p.name.c_str(), p.original,
                      t, oe, os, oee, p.oe_status.c_str(), cm, cme, lm, lme);
        }
        if (res.output_error)
          std::printf("  corr(nu12, d31) of the output-error fit: %+.3f; fitted %s\n",
                      res.output_error->corr_nu12_d31,
                      update::damping_summary(*res.output_error).c_str());
      }
      if (res.diagnosis) print_diagnosis(std::cout, *res.diagnosis);
      if (!res.damping_from_resonances.empty())
        std::cout << "  damping from the resonances: " << res.damping_from_resonances << "\n";
      for (const auto& w : res.warnings) std::cout << "  warning: " << w << "\n";
      std::cout << "\n  capture: " << res.capture_path << " (inspect: piezobench capture info " << res.capture_path
                << ")\n";
    });
  });
}

}  // namespace piezo::cli
