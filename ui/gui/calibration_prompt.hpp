#pragma once
// Fixture calibration in the GUI (issue 10): the plan panel's controls
// (which standards, the load's value) and the modal dialog that asks the
// technician to connect each standard while the job's worker thread waits
// (jobs/operator_prompt.hpp). On the simulated bench the job switches the
// standards itself and the dialog never shows.
#include <imgui.h>

#include "jobs/operator_prompt.hpp"
#include "jobs/pipeline/pipeline.hpp"

namespace piezo::gui {

struct CalibrationForm {
  bool enabled = false;
  bool open = true, shrt = true, load = true;
  double load_ohm = 1000.0;
  double load_parallel_pf = 0.0;
};

// Plan panel section: "Fixture calibration" with the standards and the load value.
void render_calibration_controls(CalibrationForm& form, bool busy);

// Puts the chosen standards and the prompt into a pipeline request.
void attach_calibration(const CalibrationForm& form, jobs::OperatorPrompt& prompt,
                        jobs::PipelineRequest& req);

// Frame loop: the modal "Connect the standard" dialog while the worker waits.
void render_calibration_prompt(jobs::OperatorPrompt& prompt);

}  // namespace piezo::gui
