// `piezobench measure`: runs a measurement plan on a bench (embedded simulator,
// SCPI over TCP, or USBTMC) and writes the capture shot by shot.
// `piezobench sim-instrument`: serves the simulated AWG and DAQ over TCP
// (AWG on PORT, DAQ on PORT+1), speaking the same SCPI dialects as the real
// ones; the AWG speaks Keysight 33500 (default) or Tektronix AWG5000 (--dialect);
// --dialect redpitaya serves one Red Pitaya STEMlab 125-14 on PORT alone
// (generator and acquisition on one SCPI server, as on the board's port 5000).
#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>
#include <thread>
#include <vector>

#include "acquisition/calibration_plan.hpp"
#include "acquisition/runner.hpp"
#include "acquisition/sim_setup.hpp"
#include "drivers/instrument_uri.hpp"
#include "drivers/sim/disturbances.hpp"
#include "drivers/sim/sim_awg.hpp"
#include "drivers/sim/sim_daq.hpp"
#include "drivers/sim/sim_redpitaya.hpp"
#include "drivers/sim/sim_tektronix_awg.hpp"
#include "drivers/sim/tcp_server.hpp"
#include "drivers/transport.hpp"
#include "model/effects.hpp"
#include "model/seed_circuit.hpp"
#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

namespace {

struct SimOptions {
  std::vector<std::string> effects;
  std::string disturbance;  // issue 33's option string (drivers/sim/disturbances.hpp)
  std::string material = "apc850";
  bool isotropic = false;
  std::string set;
  double noise = 0.0;
  double beta = 1e-7;
  std::uint64_t seed = 1;
  int adc_bits = 14;
};

void add_sim_options(CLI::App* cmd, SimOptions& o) {
  cmd->add_option("--effect", o.effects,
                  "Simulated bench effect NAME=VALUE (SI, repeatable); NAME: " + model::effect_names());
  cmd->add_option(
      "--disturbance", o.disturbance,
      "Simulated bench's slow disturbances: offset=V,offset_shot=V,hum=V[,mains=50|60],pink=PCT,drift=PCT,"
      "step=PCT@SHOT,jitter=SAMPLES (any subset; acquisition/README.md)");
  cmd->add_option("--sim-material", o.material, "Simulated transducer's material preset")->capture_default_str();
  cmd->add_flag("--sim-isotropic", o.isotropic, "Simulated transducer in the seed's isotropic class");
  cmd->add_option("--sim-set", o.set, "Simulated material overrides, e.g. YE11=6.66e10,d31=-210e-12");
  cmd->add_option("--noise", o.noise, "White noise per channel, std(noise)/std(signal)")->capture_default_str();
  cmd->add_option("--rayleigh-beta", o.beta, "Simulated Rayleigh beta (s)")->capture_default_str();
  cmd->add_option("--seed", o.seed, "Noise seed")->capture_default_str();
  cmd->add_option("--adc-bits", o.adc_bits, "Simulated DAQ resolution")->capture_default_str();
}

acq::SimSpec sim_spec(const SimOptions& o, const model::TubeGeometry& g) {
  acq::SimSpec s;
  s.material = o.material;
  s.isotropic = o.isotropic;
  s.set = o.set;
  s.geometry = g;
  s.damping.beta = o.beta;
  s.noise_rel = o.noise;
  s.seed = o.seed;
  s.adc_bits = o.adc_bits;
  for (const auto& e : o.effects) model::apply_effect_assignment(s.effects, e);
  s.disturbances = drivers::sim::parse_disturbances(o.disturbance);  // throws naming the bad key
  return s;
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

// The next step when an instrument cannot be reached: `what` is the transport's
// message ("tcp://127.0.0.1:5999: cannot connect: Connection refused"),
// `instrument` the --instrument address.
std::string unreachable_advice(const std::string& what, const std::string& instrument) {
  const auto sep = what.find(": ");
  const std::string addr = sep == std::string::npos ? instrument : what.substr(0, sep);
  const bool tcp = addr.rfind("tcp://", 0) == 0;
  std::string port = "PORT";
  if (tcp && instrument.rfind("tcp://", 0) == 0) {
    const auto colon = instrument.rfind(':');
    if (colon != std::string::npos && colon > 5) port = instrument.substr(colon + 1);
  }
  std::string head;
  if (what.find("Connection refused") != std::string::npos)
    head = "the instrument at " + addr + " refused the connection (nothing listens on that port)";
  else if (what.find("timed out") != std::string::npos)
    head = "the instrument at " + addr + " did not answer in time";
  else if (what.find("cannot resolve host") != std::string::npos)
    head = "the host of " + addr + " is unknown (" + what.substr(what.rfind(": ") + 2) + ")";
  else
    head = "the instrument at " + addr + " cannot be reached (" + what.substr(sep == std::string::npos ? 0 : sep + 2) +
           ")";
  if (!tcp)
    return head + ". Check that it is switched on and plugged in, the VID:PID (lsusb) and your access to "
                  "the USB device (udev rule); `piezobench instruments` lists the drivers.";
  return head + ". Check that the instrument is switched on and on this network, and the address and port "
                "(raw SCPI: 5025 on Keysight and Tektronix, 5000 on a Red Pitaya; the DAQ at PORT+1 unless --daq "
                "says otherwise). For the simulated bench over TCP, start `piezobench sim-instrument --port " +
         port + "` first (it serves the AWG on that port and the DAQ on the next), or measure with "
                "--instrument sim.";
}

}  // namespace

void register_measure_commands(CLI::App& app, Context& ctx) {
  // ---------------------------------------------------------------- measure
  auto* m = app.add_subcommand("measure", "Acquire a capture on the bench");
  struct MeasureArgs {
    std::string instrument = "sim";
    std::string daq;
    std::string plan_file;
    std::string excitation = "exp_decay";
    double amplitude = 1.0, decay = 3000.0, frequency = 50e3, f_start = 1e3, f_stop = 120e3, f_step = 0;
    std::size_t samples = 20000, pretrigger = 200;
    double rate = 1e7, range = 0, r1 = model::kSeedR1Ohm;
    int shots = 1;
    std::string out;
    bool overwrite = false, allow_clipping = false;
    std::string calibrate;  // "open,short,load" (issue 10)
    double load_ohm = 1000.0;
    std::optional<double> load_parallel_f;
    SimOptions sim;
  };
  auto a = std::make_shared<MeasureArgs>();
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
      acq::MeasurementPlan plan;
      if (*plan_opt) {
        plan = acq::load_plan_toml(a->plan_file);
      } else {
        auto e = acq::parse_excitation(a->excitation);
        if (!e || *e == acq::Excitation::Arbitrary)
          throw InputError("--excitation: expected exp_decay, sine, chirp or noise");
        plan.excitation.kind = *e;
        plan.excitation.amplitude_v = a->amplitude;
        plan.excitation.decay_per_s = a->decay;
        plan.excitation.frequency_hz = a->frequency;
        plan.excitation.f_start_hz = a->f_start;
        plan.excitation.f_stop_hz = a->f_stop;
        plan.excitation.f_step_hz = a->f_step;
        plan.samples = a->samples;
        plan.pretrigger_samples = a->pretrigger;
        plan.sample_rate_hz = a->rate;
        plan.range_v = a->range;
        plan.shots = a->shots;
        plan.setup.divider_r1_ohm = a->r1;
      }
      plan.validate();
      std::error_code ec;
      if (!a->overwrite && std::filesystem::exists(a->out, ec))  // before any instrument is touched
        throw InputError(a->out + " already exists: give --overwrite to replace it, or another --out");
      acq::BenchAddress addr{a->instrument, a->daq.empty() ? std::nullopt : std::optional(a->daq)};
      std::shared_ptr<drivers::sim::SimBench> sim;
      if (drivers::is_sim_address(a->instrument)) {
        sim = acq::make_sim_bench(sim_spec(a->sim, plan.setup.geometry()), plan.setup.divider_r1_ohm);
        if (!plan.setup.material) plan.setup.material = a->sim.material;
      } else if (!a->sim.effects.empty()) {
        throw InputError("--effect applies to the simulated bench only (--instrument sim)");
      } else if (!a->sim.disturbance.empty()) {
        throw InputError(
            "--disturbance applies to the simulated bench only (--instrument sim; "
            "or serve it with sim-instrument --disturbance)");
      }
      acq::Bench bench;
      try {
        bench = acq::open_bench(addr, sim);
      } catch (const drivers::TransportError& e) {
        throw drivers::TransportError(e.kind(), unreachable_advice(e.what(), a->instrument));
      }
      acq::RunnerOptions ro;
      ro.overwrite = a->overwrite;
      ro.stop_on_clipping = !a->allow_clipping;
      ro.software = "piezobench measure";
      if (!a->calibrate.empty()) {  // fixture standards before the DUT shots
        try {
          ro.calibration = acq::parse_calibration_list(a->calibrate, a->load_ohm, a->load_parallel_f);
        } catch (const std::invalid_argument& e) {
          throw InputError(e.what());
        }
        ro.connect_standard = acq::make_standard_connector(bench, terminal_prompt);
      }
      std::signal(SIGINT, on_sigint);
      ProgressBar bar("measure");
      acq::RunResult res;
      try {
        res = acq::run_measurement(bench, plan, a->out, ro,
                                   [&](const acq::Progress& p) {
                                     bar.update(static_cast<double>(p.shot) / p.total,
                                                "shot " + std::to_string(p.shot + 1) + "/" +
                                                    std::to_string(p.total) + " " + p.stage);
                                   },
                                   &g_cancel);
      } catch (const acq::RunError& e) {
        bar.finish();
        throw InputError(e.what());
      }
      bar.update(1.0);
      bar.finish();
      nlohmann::json j = {{"capture", res.capture.string()},
                          {"shots_written", res.shots_written},
                          {"shots_planned", res.shots_planned},
                          {"cancelled", res.cancelled},
                          {"clipped_shots", res.clipped_shots},
                          {"bench", bench.description}};
      if (!ro.calibration.empty()) {
        nlohmann::json cal = nlohmann::json::array();
        for (const auto& c : ro.calibration) cal.push_back(std::string(acq::to_string(c.role)));
        j["calibration"] = cal;
        j["standards_switched_by"] = acq::is_simulated_instrument(bench) ? "simulator (SIM:DUT)" : "technician";
      }
      if (ctx.json) print_json(j);
      else
        std::cout << "wrote " << res.shots_written << "/" << res.shots_planned << " shots to "
                  << res.capture.string() << " (" << bench.description << ")\n";
      if (res.cancelled) ctx.exit_code = kInternal;
    });
  });

  // --------------------------------------------------------- sim-instrument
  auto* s = app.add_subcommand("sim-instrument",
                               "Serve the simulated AWG (PORT) and DAQ (PORT+1) over TCP, or with --dialect redpitaya one instrument with both roles on PORT (SCPI; the simulator-only SIM:DUT TUBE|OPEN|SHORT|LOAD,<ohm>[,<F>] on the AWG port swaps the device for calibration standards)");
  struct SimArgs {
    std::string host = "127.0.0.1";
    int port = 5025;
    double r1 = model::kSeedR1Ohm;
    double seconds = 0;  // 0 = until interrupted
    std::string dialect = "keysight";
    SimOptions sim;
  };
  auto sa = std::make_shared<SimArgs>();
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
      if (sa->port < 1 || sa->port > 65534) throw InputError("--port must be 1..65534");
      const acq::SimSpec spec = sim_spec(sa->sim, model::TubeGeometry{});
      if (spec.disturbances.drift_rel != 0.0)  // a SCPI session does not tell the bench its capture
        std::cerr
            << "sim-instrument: note: drift needs the capture's shot count, which a client over "
               "SCPI does not send: no drift is applied (step counts the acquisitions)\n";
      auto bench = acq::make_sim_bench(spec, sa->r1);
      std::signal(SIGINT, on_sigint);
      std::signal(SIGTERM, on_sigint);
      const auto port = static_cast<std::uint16_t>(sa->port);
      std::vector<std::unique_ptr<drivers::sim::TcpServer>> servers;
      // A port in use or a host that is not an address: the user's to fix (exit 2), with the next step.
      auto serve = [&](std::shared_ptr<drivers::sim::ScpiDevice> dev, std::uint16_t p) {
        try {
          servers.push_back(std::make_unique<drivers::sim::TcpServer>(std::move(dev), sa->host, p));
        } catch (const std::runtime_error& e) {
          const std::string what = e.what();
          if (what.find("cannot listen") != std::string::npos)
            throw InputError(what + ". Another program (another sim-instrument?) may hold the port: choose another "
                                    "--port (the DAQ takes PORT+1 too), or stop that program");
          if (what.find("not an IPv4 address") != std::string::npos)
            throw InputError(what + ": give --host as a dotted IPv4 address, e.g. 127.0.0.1 or 0.0.0.0");
          throw;
        }
      };
      if (sa->dialect == "redpitaya") {  // one instrument, both roles, one port
        std::shared_ptr<drivers::sim::ScpiDevice> dev;
        try {
          dev = std::make_shared<drivers::sim::SimRedPitaya>(bench);
        } catch (const std::invalid_argument& e) {
          throw InputError(std::string(e.what()) + " (--adc-bits)");
        }
        serve(dev, port);
        servers.back()->start();
        if (ctx.json)
          print_json({{"port", servers[0]->port()}, {"awg_port", servers[0]->port()},
                      {"daq_port", servers[0]->port()}, {"host", sa->host}, {"awg_dialect", sa->dialect}});
        else
          std::cout << "simulated bench: Red Pitaya STEMlab 125-14 (generator and acquisition) on "
                    << sa->host << ":" << servers[0]->port() << std::endl;
      } else {
        const bool tek = sa->dialect == "tektronix";
        std::shared_ptr<drivers::sim::ScpiDevice> awg_dev;
        if (tek) awg_dev = std::make_shared<drivers::sim::SimTektronixAwg>(bench);
        else awg_dev = std::make_shared<drivers::sim::SimAwg>(bench);
        const char* awg_name = tek ? "Tektronix AWG5014C" : "Keysight 33522B";
        serve(awg_dev, port);
        serve(std::make_shared<drivers::sim::SimDaq>(bench), static_cast<std::uint16_t>(port + 1));
        for (auto& srv : servers) srv->start();
        if (ctx.json)
          print_json({{"awg_port", servers[0]->port()}, {"daq_port", servers[1]->port()}, {"host", sa->host},
                      {"awg_dialect", sa->dialect}});
        else
          std::cout << "simulated bench: AWG (" << awg_name << " dialect) on " << sa->host << ":"
                    << servers[0]->port() << ", DAQ (Infiniium dialect) on " << sa->host << ":"
                    << servers[1]->port() << std::endl;
      }
      auto t0 = std::chrono::steady_clock::now();
      while (!g_cancel) {
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
        if (sa->seconds > 0 &&
            std::chrono::steady_clock::now() - t0 > std::chrono::duration<double>(sa->seconds))
          break;
      }
    });
  });
}

}  // namespace piezo::cli
