// The pipeline's work, counted (see work.hpp).
#include "jobs/pipeline/work.hpp"

#include <chrono>

#include "dsp/work_counters.hpp"
#include "model/work_counters.hpp"

namespace piezo::jobs {

WorkCounts work_now() {
  return {model::modal_solves(), dsp::prony_decompositions(), dsp::ffts(), model::reduced_port_models()};
}

WorkCounts work_since(const WorkCounts& a, const WorkCounts& b) {
  return {a.modal_solves - b.modal_solves, a.prony_decompositions - b.prony_decompositions, a.ffts - b.ffts,
          a.reduced_port_models - b.reduced_port_models};
}

namespace {
double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The phase a progress label belongs to: the words before its colon ("acquire:
// shot 3/64 fetch" → "acquire"; the gap diagnosis' steps → "diagnose"), the
// update's two fits apart ("update: output-error fit").
std::string phase_of(const std::string& label) {
  const auto colon = label.find(':');
  std::string key = label.substr(0, colon);
  if (key == "update") return label;
  if (key == "gap") return "diagnose";
  return key;
}
}  // namespace

void WorkLog::open(const std::string& label) {
  const std::string phase = phase_of(label);
  if (running_ && phases_.back().phase == phase) return;  // the same phase goes on
  close();
  phases_.push_back({phase, {}, 0.0});
  start_ = work_now();
  t0_ = now_s();
  running_ = true;
}

void WorkLog::close() {
  if (!running_) return;
  phases_.back().work = work_since(work_now(), start_);
  phases_.back().seconds = now_s() - t0_;
  running_ = false;
}

}  // namespace piezo::jobs
