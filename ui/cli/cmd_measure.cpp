// `piezobench measure`: runs a measurement plan on a bench (embedded simulator,
// SCPI over TCP, or USBTMC) and writes the capture shot by shot.
// `piezobench sim-instrument`: serves the simulated AWG and DAQ over TCP
// (AWG on PORT, DAQ on PORT+1), speaking the same SCPI dialects as the real
// ones; the AWG speaks Keysight 33500 (default) or Tektronix AWG5000 (--dialect);
// --dialect redpitaya serves one Red Pitaya STEMlab 125-14 on PORT alone
// (generator and acquisition on one SCPI server, as on the board's port 5000).
// The CLI's room (ui/cli): options and printing only; the work is
// jobs/measure/ (measure_job.hpp, sim_instrument_job.hpp, sim_bench.hpp).
#include <atomic>
#include <csignal>
#include <iostream>
#include <memory>

#include "jobs/measure/measure_job.hpp"
#include "jobs/measure/sim_instrument_job.hpp"
#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

namespace {

void add_sim_options(CLI::App* cmd, jobs::SimBenchRequest& o) {
  cmd->add_option("--effect", o.effects,
                  "Simulated bench effect NAME=VALUE (SI, repeatable); NAME: " + jobs::sim_effect_names());
  cmd->add_option(
      "--disturbance", o.disturbance,
      "Simulated bench's slow disturbances: offset=V,offset_shot=V,hum=V[,mains=50|60],pink=PCT,drift=PCT,"
      "step=PCT@SHOT,jitter=SAMPLES (any subset; acquisition/README.md)");
  cmd->add_option("--sim-material", o.material, "Simulated transducer's material preset")->capture_default_str();
  cmd->add_flag("--sim-isotropic", o.isotropic, "Simulated transducer in the seed's isotropic class");
  cmd->add_option("--sim-set", o.set, "Simulated material overrides, e.g. YE11=6.66e10,d31=-210e-12");
  cmd->add_option("--noise", o.noise, "White noise per channel, std(noise)/std(signal)")->capture_default_str();
  cmd->add_option("--rayleigh-beta", o.rayleigh_beta, "Simulated Rayleigh beta (s)")->capture_default_str();
  cmd->add_option("--seed", o.seed, "Noise seed")->capture_default_str();
  cmd->add_option("--adc-bits", o.adc_bits, "Simulated DAQ resolution")->capture_default_str();
}

std::atomic<bool> g_cancel{false};
void on_sigint(int) { g_cancel = true; }

// Asks the technician on the terminal to connect a standard; 'q' cancels.
bool terminal_prompt(const std::string& instruction) {
  std::cerr << "\n>>> " << instruction << "\n    press Enter when done (q + Enter cancels): " << std::flush;
  std::string line;
  if (!std::getline(std::cin, line)) return false;  // no terminal input: nobody connected it
  return line != "q" && line != "Q";
}

}  // namespace

void register_measure_command(CLI::App& app, Context& ctx) {
  auto* m = app.add_subcommand("measure", "Acquire a capture on the bench");
  auto a = std::make_shared<jobs::MeasureRequest>();
  m->add_option("--instrument", a->instrument,
                "sim | sim?awg=tektronix | tcp://HOST:PORT | usbtmc://VID:PID[/SERIAL] (the AWG)")
      ->capture_default_str();
  m->add_option(
      "--daq", a->daq,
      "DAQ address (default: the instrument itself if it has both roles, e.g. a Red Pitaya; "
      "else tcp PORT+1 on the same host), or a board through Comedi: "
      "comedi:///dev/comediN?trigger=pfi0&aref=diff&channels=0,1 (comedi-sim:// on the embedded "
      "bench)");
  auto* plan_opt = m->add_option("--plan", a->plan_file, "TOML measurement plan");
  m->add_option("--excitation", a->excitation, "exp_decay | sine | chirp | noise")->capture_default_str();
  m->add_option("--amplitude", a->amplitude, "Peak drive (V)")->capture_default_str();
  m->add_option("--decay", a->decay, "exp_decay rate (1/s)")->capture_default_str();
  m->add_option("--frequency", a->frequency, "sine frequency (Hz)")->capture_default_str();
  m->add_option("--f-start", a->f_start, "chirp / stepped-sine start (Hz)");
  m->add_option("--f-stop", a->f_stop, "chirp / stepped-sine stop (Hz)");
  m->add_option("--f-step", a->f_step, "stepped-sine step (Hz); > 0 makes one shot per frequency");
  m->add_option("--samples", a->samples, "Record length")->capture_default_str();
  m->add_option("--pretrigger", a->pretrigger, "Samples before the trigger")->capture_default_str();
  m->add_option("--rate", a->rate, "Sample rate (S/s)")->capture_default_str();
  m->add_option("--range", a->range, "DAQ ±range (V); 0 = 1.25 × amplitude")->capture_default_str();
  m->add_option("--r1", a->r1, "Series resistor R1 (ohm)")->capture_default_str();
  m->add_option("--shots", a->shots, "Shots per excitation step")->capture_default_str();
  m->add_option("--out", a->out, "Capture file to write (.h5)")->required();
  m->add_flag("--overwrite", a->overwrite, "Replace an existing capture (without it an existing --out is an error)");
  m->add_flag("--allow-clipping", a->allow_clipping, "Keep going after a clipped shot");
  m->add_option("--calibrate", a->calibrate,
                "Measure fixture standards first, e.g. open,short,load (the simulator swaps them itself; "
                "on a real bench you are asked to connect each)");
  m->add_option("--load-ohm", a->load_ohm, "Resistance of the load standard (ohm)")->capture_default_str();
  m->add_option("--load-parallel-f", a->load_parallel_f, "Parallel capacitance of the load standard (F)");
  add_sim_options(m, a->sim);
  add_json_flag(m, ctx);
  m->callback([&ctx, a, plan_opt] {
    ctx.exit_code = run_command(ctx, [&] {
      jobs::MeasureRequest req = *a;
      if (!*plan_opt) req.plan_file.clear();
      ProgressBar bar("measure");
      jobs::MeasureCallbacks cb;
      cb.progress = [&](const acq::Progress& p) {
        bar.update(static_cast<double>(p.shot) / p.total,
                   "shot " + std::to_string(p.shot + 1) + "/" + std::to_string(p.total) + " " + p.stage);
      };
      cb.prompt = terminal_prompt;
      cb.cancel = &g_cancel;
      cb.on_run = [] { std::signal(SIGINT, on_sigint); };
      const jobs::MeasureResult res = jobs::run_measure(req, cb);
      bar.update(1.0);
      bar.finish();
      if (ctx.json) print_json(jobs::measure_json(res));
      else
        std::cout << "wrote " << res.run.shots_written << "/" << res.run.shots_planned << " shots to "
                  << res.run.capture.string() << " (" << res.bench << ")\n";
      if (res.run.cancelled) ctx.exit_code = kInternal;
    });
  });
}

void register_sim_instrument_command(CLI::App& app, Context& ctx) {
  auto* s = app.add_subcommand("sim-instrument",
                               "Serve the simulated AWG (PORT) and DAQ (PORT+1) over TCP, or with --dialect redpitaya one instrument with both roles on PORT (SCPI; the simulator-only SIM:DUT TUBE|OPEN|SHORT|LOAD,<ohm>[,<F>] on the AWG port swaps the device for calibration standards)");
  auto sa = std::make_shared<jobs::SimInstrumentRequest>();
  s->add_option("--host", sa->host, "IPv4 address to listen on")->capture_default_str();
  s->add_option("--port", sa->port, "AWG port; the DAQ listens on PORT+1")->capture_default_str();
  s->add_option("--r1", sa->r1, "Nominal series resistor of the simulated bench (ohm)")->capture_default_str();
  s->add_option("--seconds", sa->seconds, "Stop after this long (0: until Ctrl-C)")->capture_default_str();
  s->add_option("--dialect", sa->dialect,
                "The AWG's SCPI dialect: keysight (33522B) or tektronix (AWG5014C), the DAQ being Infiniium "
                "on PORT+1; or redpitaya (STEMlab 125-14: both roles on PORT alone)")
      ->check(CLI::IsMember({"keysight", "tektronix", "redpitaya"}))
      ->capture_default_str();
  add_sim_options(s, sa->sim);
  add_json_flag(s, ctx);
  s->callback([&ctx, sa] {
    ctx.exit_code = run_command(ctx, [&] {
      jobs::SimInstrumentCallbacks cb;
      cb.note = [](const std::string& n) { std::cerr << "sim-instrument: note: " << n << "\n"; };
      cb.listening = [&](const jobs::SimInstrumentListening& at) {
        std::signal(SIGINT, on_sigint);
        std::signal(SIGTERM, on_sigint);
        if (at.one_instrument) {
          if (ctx.json)
            print_json({{"port", at.awg_port}, {"awg_port", at.awg_port}, {"daq_port", at.daq_port},
                        {"host", sa->host}, {"awg_dialect", sa->dialect}});
          else
            std::cout << "simulated bench: " << at.awg_name << " (generator and acquisition) on " << sa->host << ":"
                      << at.awg_port << std::endl;
        } else if (ctx.json) {
          print_json({{"awg_port", at.awg_port}, {"daq_port", at.daq_port}, {"host", sa->host},
                      {"awg_dialect", sa->dialect}});
        } else {
          std::cout << "simulated bench: AWG (" << at.awg_name << " dialect) on " << sa->host << ":" << at.awg_port
                    << ", DAQ (Infiniium dialect) on " << sa->host << ":" << at.daq_port << std::endl;
        }
      };
      cb.cancel = &g_cancel;
      jobs::run_sim_instrument(*sa, cb);
    });
  });
}

}  // namespace piezo::cli
