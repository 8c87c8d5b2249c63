#pragma once
// The pipeline's work, counted (issue 43 item 3): FE modal solves
// (model/work_counters.hpp), Prony-SS decompositions and FFTs
// (dsp/work_counters.hpp), per phase of the run (the progress callback's
// stages: acquire, estimate, update, diagnose, …). Deterministic for a given
// capture, so the tests assert them and a change that doubles the work fails
// CI without a timing assertion; `work` in every report (report_json).
#include <string>
#include <vector>

namespace piezo::jobs {

struct WorkCounts {
  long modal_solves = 0;          // ModalSolver::solve calls (a port model: two)
  long prony_decompositions = 0;  // Hankel SVDs (any order, bootstrap replicate or stabilization row)
  long ffts = 0;                  // real FFTs executed
  long reduced_port_models = 0;   // port models from a reduced basis (model/reduced_port.hpp), no modal solve
  WorkCounts& operator+=(const WorkCounts& o) {
    modal_solves += o.modal_solves;
    prony_decompositions += o.prony_decompositions;
    ffts += o.ffts;
    reduced_port_models += o.reduced_port_models;
    return *this;
  }
};

// The process's totals so far.
WorkCounts work_now();
// a − b, field by field.
WorkCounts work_since(const WorkCounts& a, const WorkCounts& b);

struct WorkPhase {
  std::string phase;  // "acquire", "estimate", "update: output-error fit", "diagnose", …
  WorkCounts work;
  double seconds = 0;  // wall time (not deterministic: never compared by the tests)
};

// Records the work between progress labels: open() closes the phase running
// and opens the label's (consecutive labels of one phase add up); close()
// ends the last.
class WorkLog {
 public:
  void open(const std::string& label);
  void close();
  const std::vector<WorkPhase>& phases() const { return phases_; }

 private:
  std::vector<WorkPhase> phases_;
  WorkCounts start_{};
  double t0_ = 0;
  bool running_ = false;
};

}  // namespace piezo::jobs
