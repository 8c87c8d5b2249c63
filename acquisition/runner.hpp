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
#include "acquisition/plan.hpp"

namespace piezo::acq {

struct RunnerOptions {
  bool stop_on_clipping = true;  // a clipped shot is stored (flagged), then the run stops
  double fetch_timeout_s = 10.0;
  std::string software = "piezobench";
  bool overwrite = false;
  // Ground truth of a simulated bench, written under /truth (tests only).
  bool record_truth = true;
};

struct Progress {
  int shot = 0;  // 0-based, the shot being worked on
  int total = 0;
  std::string stage;  // "configure", "acquire", "fetch", "write"
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
