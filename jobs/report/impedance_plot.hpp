#pragma once
// The impedance overlay of one pipeline result as a plot: |Z| (log–log) and
// phase over a log frequency axis; the measured (Prony-SS) estimate, original
// and updated model; resonance and anti-resonance markers. The headless twin
// of the GUI's plots window (ui/gui/plots_window.cpp) in its default view.
#include "jobs/pipeline/pipeline.hpp"
#include "jobs/report/plot_cairo.hpp"

namespace piezo::jobs::report {

Figure impedance_figure(const jobs::PipelineResult& r, const std::string& title);

}  // namespace piezo::jobs::report
