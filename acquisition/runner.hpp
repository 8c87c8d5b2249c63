#pragma once
// The measurement runner: for every shot of a plan it configures the AWG and
// the DAQ, arms, triggers, fetches, checks clipping, and appends the shot to
// the capture file at once (flushed), reporting progress and honouring
// cancellation. Whatever goes wrong, the shots already acquired stay in the
// capture.
#include <atomic>
#include <functional>
#include <string>

#include "acquisition/bench.hpp"
#include "acquisition/calibration_plan.hpp"
#include "acquisition/plan.hpp"

namespace piezo::acq {

struct RunnerOptions {
  bool stop_on_clipping = true;  // a clipped shot is stored (flagged), then the run stops
  double fetch_timeout_s = 10.0;
  std::string software = "piezobench";
  bool overwrite = false;
  // Ground truth of a simulated bench, written under /truth (tests only).
  bool record_truth = true;
  // Fixture calibration (calibration_plan.hpp): before the DUT shots, each
  // standard is connected through `connect_standard` and measured with the
  // plan's excitation steps and shots, its shots carrying the standard's
  // `role` (and load values); then the transducer is connected again (a step
  // of role Dut). Empty: DUT shots only. connect_standard returning false cancels.
  std::vector<CalibrationStep> calibration;
  StandardConnector connect_standard;
  // Before a standard's shots, one unrecorded shot sets channel 2's range to
  // its signal (a short gives millivolts: at the drive's range the ADC would
  // resolve it in a few codes). Channel 1 keeps the plan's range.
  bool autorange_standards = true;
};

struct Progress {
  int shot = 0;  // 0-based, the shot being worked on
  int total = 0;
  std::string stage;  // "configure", "acquire", "fetch", "write"; "connect open|short|load|dut"
};

struct RunResult {
  std::filesystem::path capture;
  int shots_written = 0;
  int shots_planned = 0;
  bool cancelled = false;
  std::vector<int> clipped_shots;
};

// Thrown when the run stops on an error after writing some shots: says which
// shot failed, why, and where the acquired shots are.
class RunError : public std::runtime_error {
 public:
  RunError(const std::string& msg, RunResult partial) : std::runtime_error(msg), partial_(std::move(partial)) {}
  const RunResult& partial() const { return partial_; }

 private:
  RunResult partial_;
};

RunResult run_measurement(Bench& bench, const MeasurementPlan& plan, const std::filesystem::path& out,
                          const RunnerOptions& opt = {},
                          const std::function<void(const Progress&)>& progress = {},
                          const std::atomic<bool>* cancel = nullptr);

}  // namespace piezo::acq
