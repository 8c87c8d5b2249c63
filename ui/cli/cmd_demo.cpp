// `piezobench demo`: runs every stage that has landed, end to end, on the
// embedded simulated bench. Stages so far: capture files.
// TODO(issue 5): replace the analytic RC stand-in by the simulated bench.
#include <cmath>
#include <filesystem>
#include <iostream>

#include "acquisition/capture_file.hpp"
#include "dsp/signal_stats.hpp"
#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

namespace {

constexpr double kEps0 = 8.854187817e-12;

// Exact response of the divider with a lossless capacitor as the load to the
// seed's exp_decay drive v1 = A·exp(−a·t): v2 = A/(1 − a·τ)·(e^{−a t} − e^{−t/τ}), τ = R1·C.
acq::Shot rc_exp_decay_shot(double r1, double c, double amplitude, double decay, double rate,
                            std::size_t n, std::size_t pretrigger) {
  acq::Shot s;
  s.sample_rate_hz = rate;
  s.excitation = acq::Excitation::ExpDecay;
  s.amplitude_v = amplitude;
  s.decay_per_s = decay;
  s.pretrigger_samples = static_cast<std::int64_t>(pretrigger);
  s.v1.assign(n, 0.0);
  s.v2.assign(n, 0.0);
  const double tau = r1 * c;
  for (std::size_t i = pretrigger; i < n; ++i) {
    double t = (i - pretrigger) / rate;
    s.v1[i] = amplitude * std::exp(-decay * t);
    s.v2[i] = amplitude / (1.0 - decay * tau) * (std::exp(-decay * t) - std::exp(-t / tau));
  }
  return s;
}

}  // namespace

void register_demo_command(CLI::App& app, Context& ctx) {
  auto* demo = app.add_subcommand("demo", "Run the main job on the embedded simulated bench");
  auto out_dir = std::make_shared<std::string>("demo-out");
  demo->add_option("--out", *out_dir, "Folder for the demo's files")->capture_default_str();
  add_json_flag(demo, ctx);
  demo->callback([&ctx, out_dir] {
    ctx.exit_code = run_command(ctx, [&] {
      namespace fs = std::filesystem;
      fs::create_directories(*out_dir);
      const fs::path cap_path = fs::path(*out_dir) / "demo-capture.h5";

      // Stage 1 — acquire (stand-in: the tube as its static capacitance).
      acq::Setup setup;
      setup.divider_r1_ohm = 3140.0;  // seed §5.2 lab circuit
      setup.transducer_id = "demo-tube";
      setup.material = "apc850";
      auto g = setup.geometry();
      const double c0 = 2 * M_PI * 1594 * kEps0 * g.length_m /
                        std::log(g.outer_diameter_m / g.inner_diameter_m);
      acq::WriterOptions wo;
      wo.software = "piezobench demo";
      wo.overwrite = true;
      {
        ProgressBar bar("acquire");
        acq::CaptureWriter w(cap_path, setup, wo);
        const int kShots = 3;
        for (int k = 0; k < kShots; ++k) {
          w.append(rc_exp_decay_shot(setup.divider_r1_ohm, c0, 1.0, 3000.0, 1e7, 20000, 200));
          bar.update((k + 1.0) / kShots);
        }
        w.close();
      }

      // Stage 2 — read back and summarise.
      auto cap = acq::read_capture(cap_path);
      nlohmann::json j;
      j["capture"] = cap_path.string();
      j["shots"] = cap.shots.size();
      j["stages"] = {"acquire", "capture-file"};
      j["tube_capacitance_f"] = c0;
      auto st = dsp::compute_stats(cap.shots[0].v2);
      j["v2_rms_v"] = st.rms;
      if (ctx.json) {
        print_json(j);
      } else {
        std::cout << "piezobench demo\n"
                  << "  wrote " << cap_path.string() << " (" << cap.shots.size() << " shots)\n"
                  << "  stages run: acquire -> capture file\n"
                  << "  inspect it with: piezobench capture info " << cap_path.string() << "\n";
      }
    });
  });
}

}  // namespace piezo::cli
