#pragma once
// The impedance overlay of one pipeline result as a plot: |Z| (log–log) and
// phase over a log frequency axis; the measured (Prony-SS) estimate, original
// and updated model; resonance and anti-resonance markers. The headless twin
// of the GUI's plots window (ui/gui/plots_window.cpp) in its default view.
#include "ui/pipeline.hpp"
#include "ui/report/svg_plot.hpp"

namespace piezo::report {

Figure impedance_figure(const ui::PipelineResult& r, const std::string& title);

}  // namespace piezo::report
