#pragma once
// One window per file, each a render(AppState&) that only draws and edits
// state; the work behind a button goes through actions (app_state.hpp).
#include "ui/gui/app_state.hpp"
#include "ui/gui/palette.hpp"

namespace piezo::gui {

void render_instrument_window(AppState& s);
void render_plan_window(AppState& s);
void render_plots_window(AppState& s);
void render_results_window(AppState& s);
void render_diagnosis_window(AppState& s);

// A button whose screen rectangle is recorded under its label (scripted tests click it).
bool tracked_button(AppState& s, const char* label, ImVec2 size = ImVec2(0, 0));
// A checkbox whose rectangle is recorded like tracked_button's (scripted clicks).
bool tracked_checkbox(AppState& s, const char* label, bool* value);

// A problem in red with its advice below it (error_advice.hpp).
void show_problem(const Problem& p);

}  // namespace piezo::gui
