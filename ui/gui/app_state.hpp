#pragma once
// The GUI's model: what the technician edits (forms), the running job and the
// last result. Windows read and edit it; only the job thread runs work.
#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "ui/gui/calibration_prompt.hpp"
#include "ui/gui/plot_widget.hpp"
#include "ui/pipeline.hpp"

namespace piezo::gui {

// Runs the pipeline on a worker thread; the frame loop polls it.
class Job {
 public:
  ~Job();
  bool start(const ui::PipelineRequest& req);  // false if one is running
  void cancel() { cancel_ = true; }
  bool running() const { return running_; }
  float progress() const { return progress_; }
  std::string stage() const;
  // Moves a finished result (or error) out; true once per finished job.
  bool take(std::unique_ptr<ui::PipelineResult>& result, std::string& error);

 private:
  std::thread thread_;
  std::atomic<bool> running_{false}, cancel_{false}, finished_{false};
  std::atomic<float> progress_{0};
  mutable std::mutex mu_;
  std::string stage_, error_;
  std::unique_ptr<ui::PipelineResult> result_;
};

struct InstrumentForm {
  char awg[128] = "sim";
  char daq[128] = "";
  std::string idn_awg, idn_daq, state = "not connected", last_error;
};

struct AppState {
  InstrumentForm instrument;
  ui::PipelineRequest request;  // the plan panel edits this; a job gets a copy
  char capture_out[256] = "piezobench-capture.h5";
  char replay_path[256] = "";
  // Issue 10: fixture standards before the shots. The prompt is declared before
  // the job so that it outlives the job's thread, which may be waiting in it;
  // ~AppState declines that question before the job joins.
  CalibrationForm calibration;
  ui::OperatorPrompt calibration_prompt;  // the worker asks, the frame loop draws the dialog
  ~AppState() { calibration_prompt.close(); }
  Job job;
  std::unique_ptr<ui::PipelineResult> result;
  std::string error;  // shown in the window with what to do
  std::vector<std::string> log;
  PlotView mag_view{true, true}, phase_view{true, false}, sv_view{false, true};
  bool show_fft = false, show_xspec = false;
  // Screen rectangles of named buttons, for scripted input in tests.
  std::map<std::string, ImVec4> button_rects;
  char export_base[256] = "piezobench-report";
  std::string png_request;  // set by the Export PNG button, served by the frame loop after rendering
  std::vector<double> frame_ms_during_job;
};

}  // namespace piezo::gui
