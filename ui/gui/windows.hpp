#pragma once
// One window per file, each a render(AppState&) that only draws and edits state.
#include "ui/gui/app_state.hpp"

namespace piezo::gui {

void render_instrument_window(AppState& s);
void render_plan_window(AppState& s);
void render_plots_window(AppState& s);
void render_results_window(AppState& s);

// A button whose screen rectangle is recorded under its label (scripted tests click it).
bool tracked_button(AppState& s, const char* label, ImVec2 size = ImVec2(0, 0));

// Plot colours shared by the windows and the GUI test's pixel checks.
inline constexpr ImU32 kColMeasured = IM_COL32(255, 200, 40, 255);   // amber
inline constexpr ImU32 kColOriginal = IM_COL32(80, 160, 255, 255);   // blue
inline constexpr ImU32 kColUpdated = IM_COL32(60, 220, 120, 255);    // green
inline constexpr ImU32 kColFft = IM_COL32(200, 120, 255, 255);       // violet
inline constexpr ImU32 kColXspec = IM_COL32(255, 110, 110, 255);     // red

}  // namespace piezo::gui
