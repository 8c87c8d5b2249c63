#pragma once
// The jobs' room (jobs/measure/): `piezobench measure` — a measurement plan
// (TOML, or the options' exp_decay / sine / chirp / noise drive) run on a
// bench (the embedded simulated one, SCPI over TCP, USBTMC, a Comedi board),
// the fixture standards first when asked, the capture written shot by shot.
// ui/cli/cmd_measure.cpp parses the options into a MeasureRequest and prints.
#include <atomic>
#include <cstddef>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "acquisition/runner.hpp"
#include "jobs/measure/sim_bench.hpp"
#include "model/seed_circuit.hpp"

namespace piezo::jobs {

struct MeasureRequest {
  std::string instrument = "sim";  // the AWG's address: sim, sim?awg=tektronix, tcp://, usbtmc://
  std::string daq;                 // "": the instrument itself, or tcp PORT+1
  std::string plan_file;           // a TOML plan; the drive options below when empty
  std::string excitation = "exp_decay";
  double amplitude = 1.0, decay = 3000.0, frequency = 50e3, f_start = 1e3, f_stop = 120e3, f_step = 0;
  std::size_t samples = 20000, pretrigger = 200;
  double rate = 1e7, range = 0, r1 = model::kSeedR1Ohm;
  int shots = 1;
  std::string out;  // the capture to write
  bool overwrite = false, allow_clipping = false;
  std::string calibrate;  // "open,short,load" (issue 10)
  double load_ohm = 1000.0;
  std::optional<double> load_parallel_f;
  SimBenchRequest sim;  // the simulated bench's (instrument sim only)
};

struct MeasureCallbacks {
  std::function<void(const acq::Progress&)> progress;
  // Asks the technician to connect a standard; false cancels (real bench only).
  std::function<bool(const std::string& instruction)> prompt;
  const std::atomic<bool>* cancel = nullptr;
  std::function<void()> on_run;  // once the bench is open, before the first shot
};

struct MeasureResult {
  acq::RunResult run;
  std::string bench;                  // the bench's description
  std::vector<std::string> standards;  // the calibration standards measured, in order
  bool simulated = false;             // the standards were switched by the simulator
};

// Throws InputError (jobs/job_error.hpp) for a bad plan or option, an existing
// capture without `overwrite`, an option of the simulated bench with a real
// one; drivers::TransportError (with the next step in its message) for an
// instrument that cannot be reached.
MeasureResult run_measure(const MeasureRequest& req, const MeasureCallbacks& cb);

// capture, shots_written, shots_planned, cancelled, clipped_shots, bench;
// calibration and standards_switched_by when standards were measured.
nlohmann::json measure_json(const MeasureResult& r);

// The next step when an instrument cannot be reached: `what` is the
// transport's message, `instrument` the --instrument address.
std::string unreachable_advice(const std::string& what, const std::string& instrument);

}  // namespace piezo::jobs
