#pragma once
// The GUI's model: what the technician edits (forms), the running job, the
// background tasks and the last result. Windows read and edit it; only the
// Job and TaskQueue threads run work, and they hand results back through
// take() / drain() on the UI thread.
#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "ui/gui/calibration_prompt.hpp"
#include "ui/gui/error_advice.hpp"
#include "ui/gui/plot_widget.hpp"
#include "ui/gui/task_queue.hpp"
#include "jobs/measure/sim_bench.hpp"
#include "jobs/mode_nyquist.hpp"
#include "jobs/pipeline/pipeline.hpp"
#include "jobs/report/limits.hpp"

namespace piezo::gui {

// Runs the pipeline on a worker thread; the frame loop polls it.
class Job {
 public:
  ~Job();
  bool start(const jobs::PipelineRequest& req);  // false if one is running
  void cancel() { cancel_ = true; }
  bool running() const { return running_; }
  // Running, or finished with an outcome not yet taken.
  bool busy() const { return running_ || finished_; }
  bool cancel_requested() const { return cancel_; }
  float progress() const { return progress_; }
  std::string stage() const;
  // Moves a finished result (or the problem that stopped it) out; true once per finished job.
  bool take(std::unique_ptr<jobs::PipelineResult>& result, std::optional<Problem>& problem);

 private:
  std::thread thread_;
  std::atomic<bool> running_{false}, cancel_{false}, finished_{false};
  std::atomic<float> progress_{0};
  mutable std::mutex mu_;
  std::string stage_;
  std::optional<Problem> problem_;
  std::unique_ptr<jobs::PipelineResult> result_;
};

struct InstrumentForm {
  char awg[128] = "sim";
  char daq[128] = "";
  // Bench effects the simulated bench adds (NAME=VALUE, comma separated), so
  // that the gap diagnosis has something to find; see model/effects.hpp.
  char sim_effects[256] = "";
  // A real bench's slow disturbances on the simulated bench, the option string
  // of drivers::sim::parse_disturbances ("offset=0.005,hum=0.005,mains=50").
  char sim_disturbances[256] = "";
  // The simulated bench the two fields above complete (the demo's tube, set
  // at start-up from jobs::demo_sim_request; jobs/measure/sim_bench.hpp).
  jobs::SimBenchRequest sim;
  int driver_choice = 0;  // the driver combo's entry (ui/gui/driver_choices.hpp)
  // (The order is the frame statistics' numbering; tests/gui relies on it.)
  enum class State {
    NotConnected,
    Connecting,
    Connected,
    Replay,
    Error,
    Measuring,
  } state = State::NotConnected;
  State before_job =
      State::NotConnected;  // restored when a job fails for a reason not the instruments'
  std::string idn_awg, idn_daq, description;
  std::optional<Problem> problem;  // the last connection or instrument error
};

// What the diagnosis window drew in the last frame (read by the test hook).
struct DiagnosisShown {
  std::string verdict;
  int effects = 0, regions = 0;
};

struct AppState {
  InstrumentForm instrument;
  jobs::PipelineRequest request;  // the plan panel edits this; a job gets a copy
  char transducer_id[64] = "";  // recorded in the capture's set-up
  int material_index = 0;       // into jobs::material_presets(): the nominal model to update
  char capture_out[256] = "piezobench-capture.h5";
  char replay_path[256] = "";
  char heldout_path[256] = "";  // optional: the replayed capture's held-out capture (issue 18)
  // Issue 10: fixture standards before the shots. The prompt is declared before
  // the job so that it outlives the job's thread, which may be waiting in it;
  // ~AppState declines that question before the job joins.
  CalibrationForm calibration;
  jobs::OperatorPrompt calibration_prompt;  // the worker asks, the frame loop draws the dialog
  ~AppState() { calibration_prompt.close(); }
  Job job;
  int jobs_started = 0;
  bool last_job_replay = false;  // the running/last job replays a capture (its set-up goes to the Plan panel)
  // Acceptance limits (jobs/report/limits.hpp, as `replay --limits`): loaded on
  // the task thread; each finished result is judged against them.
  char limits_path[256] = "";
  std::shared_ptr<const jobs::report::Limits> limits;
  std::optional<jobs::report::CaptureVerdict> verdict;  // of `result` against `limits`
  // Shared with background exports, so a new job can replace it while one runs.
  std::shared_ptr<const jobs::PipelineResult> result;
  std::optional<Problem> error;   // stopped the last job or export; shown with what to do
  std::vector<Problem> warnings;  // of the last result, with what to do
  std::vector<std::string> log;
  // The plots' views (their scales are in the specs, plots_window.cpp).
  PlotView mag_view, phase_view, sv_view, residual_view;
  bool residual_log_f = false;  // the residual plot on a log frequency axis
  bool show_fft = false, show_xspec = false;
  // The per-mode figures and the admittance (Nyquist) view of one mode, in
  // place of the residual/phase/SV row (jobs/mode_nyquist.hpp; computed when a
  // result arrives, collect_job).
  bool show_modes = false;
  int nyquist_mode = 0;  // index into `nyquist`
  std::vector<jobs::ModeNyquist> nyquist;
  PlotView nyquist_view;
  bool residual_phase = false;  // the residual plot shows phase (deg) instead of |Z| (dB)
  DiagnosisShown diagnosis_shown;
  // Screen rectangles of named buttons, for scripted input in tests.
  std::map<std::string, ImVec4> button_rects;
  char export_base[256] = "piezobench-report";
  std::string png_request;  // set by the PNG button, read back by the frame loop after rendering
  // Frame times (ms): one list per job started, of the frames while it ran; and the others.
  std::vector<std::vector<double>> frame_ms_jobs;
  std::vector<double> frame_ms_idle;
  TaskQueue tasks;  // last: its thread stops before the state its outcomes write to goes away
};

// Starts the pipeline with the committed form values; `replay` replays the
// capture named in the plan panel instead of measuring.
void start_job(AppState& s, bool replay);

// Opens the bench in the instrument panel on the task thread (*IDN?, state).
void connect_instruments(AppState& s);

// Takes a finished job's outcome into the state (result, error, instrument
// state, log); true when a job finished this frame.
bool collect_job(AppState& s);

// Reads the limits file named in the plan panel on the task thread (a
// malformed one is an error with its line); then judges the result.
void load_limits(AppState& s);
// The result against the loaded limits (none loaded or no result: no verdict).
void judge_result(AppState& s);

// Writes the result as CSV, Touchstone or a JSON report on the task thread.
enum class ExportFormat { Csv, Touchstone, Json };
void export_result(AppState& s, ExportFormat f);

}  // namespace piezo::gui
