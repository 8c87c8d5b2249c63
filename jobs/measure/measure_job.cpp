// The jobs' room (jobs/measure/): `piezobench measure` (see measure_job.hpp).
#include "jobs/measure/measure_job.hpp"

#include <filesystem>

#include "acquisition/bench.hpp"
#include "acquisition/calibration_plan.hpp"
#include "acquisition/plan.hpp"
#include "drivers/instrument_uri.hpp"
#include "drivers/transport.hpp"
#include "jobs/job_error.hpp"

namespace piezo::jobs {

namespace {

acq::MeasurementPlan plan_of(const MeasureRequest& a) {
  acq::MeasurementPlan plan;
  if (!a.plan_file.empty()) {
    plan = acq::load_plan_toml(a.plan_file);
  } else {
    auto e = acq::parse_excitation(a.excitation);
    if (!e || *e == acq::Excitation::Arbitrary) throw InputError("--excitation: expected exp_decay, sine, chirp or noise");
    plan.excitation.kind = *e;
    plan.excitation.amplitude_v = a.amplitude;
    plan.excitation.decay_per_s = a.decay;
    plan.excitation.frequency_hz = a.frequency;
    plan.excitation.f_start_hz = a.f_start;
    plan.excitation.f_stop_hz = a.f_stop;
    plan.excitation.f_step_hz = a.f_step;
    plan.samples = a.samples;
    plan.pretrigger_samples = a.pretrigger;
    plan.sample_rate_hz = a.rate;
    plan.range_v = a.range;
    plan.shots = a.shots;
    plan.setup.divider_r1_ohm = a.r1;
  }
  plan.validate();
  return plan;
}

}  // namespace

MeasureResult run_measure(const MeasureRequest& a, const MeasureCallbacks& cb) {
  acq::MeasurementPlan plan = plan_of(a);
  std::error_code ec;
  if (!a.overwrite && std::filesystem::exists(a.out, ec))  // before any instrument is touched
    throw InputError(a.out + " already exists: give --overwrite to replace it, or another --out");
  acq::BenchAddress addr{a.instrument, a.daq.empty() ? std::nullopt : std::optional(a.daq)};
  std::shared_ptr<drivers::sim::SimBench> sim;
  if (drivers::is_sim_address(a.instrument)) {
    sim = acq::make_sim_bench(sim_spec(a.sim, plan.setup.geometry()), plan.setup.divider_r1_ohm);
    if (!plan.setup.material) plan.setup.material = a.sim.material;
  } else if (!a.sim.effects.empty()) {
    throw InputError("--effect applies to the simulated bench only (--instrument sim)");
  } else if (!a.sim.disturbance.empty()) {
    throw InputError(
        "--disturbance applies to the simulated bench only (--instrument sim; "
        "or serve it with sim-instrument --disturbance)");
  }
  acq::Bench bench;
  try {
    bench = acq::open_bench(addr, sim);
  } catch (const drivers::TransportError& e) {
    throw drivers::TransportError(e.kind(), unreachable_advice(e.what(), a.instrument));
  }
  acq::RunnerOptions ro;
  ro.overwrite = a.overwrite;
  ro.stop_on_clipping = !a.allow_clipping;
  ro.software = "piezobench measure";
  if (!a.calibrate.empty()) {  // fixture standards before the DUT shots
    try {
      ro.calibration = acq::parse_calibration_list(a.calibrate, a.load_ohm, a.load_parallel_f);
    } catch (const std::invalid_argument& e) {
      throw InputError(e.what());
    }
    ro.connect_standard = acq::make_standard_connector(bench, cb.prompt);
  }
  if (cb.on_run) cb.on_run();
  MeasureResult out;
  try {
    out.run = acq::run_measurement(bench, plan, a.out, ro, cb.progress, cb.cancel);
  } catch (const acq::RunError& e) {
    throw InputError(e.what());
  }
  out.bench = bench.description;
  for (const auto& c : ro.calibration) out.standards.push_back(std::string(acq::to_string(c.role)));
  out.simulated = acq::is_simulated_instrument(bench);
  return out;
}

nlohmann::json measure_json(const MeasureResult& r) {
  nlohmann::json j = {{"capture", r.run.capture.string()},
                      {"shots_written", r.run.shots_written},
                      {"shots_planned", r.run.shots_planned},
                      {"cancelled", r.run.cancelled},
                      {"clipped_shots", r.run.clipped_shots},
                      {"bench", r.bench}};
  if (!r.standards.empty()) {
    j["calibration"] = r.standards;
    j["standards_switched_by"] = r.simulated ? "simulator (SIM:DUT)" : "technician";
  }
  return j;
}

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

}  // namespace piezo::jobs
