#pragma once
// The per-mode figures in a capture's replay report (issue 19): a Markdown
// table with units and sigma (IEEE Std 176 / EN 50324-2 names), and the
// admittance plane of each mode — the estimate's points, the fitted BVD
// network and the motional circle (jobs/mode_nyquist.hpp) — as one SVG panel per mode.
#include <optional>
#include <string>

#include "jobs/pipeline/pipeline.hpp"
#include "jobs/report/plot_cairo.hpp"

namespace piezo::jobs::report {

// "## Per-mode figures" and its table; a line saying why when there are none.
std::string mode_figures_markdown(const jobs::PipelineResult& r);
// One panel per mode with a converged BVD fit (at most `max_modes`); none
// without figures.
std::optional<Figure> nyquist_figure(const jobs::PipelineResult& r, int max_modes = 4);

}  // namespace piezo::jobs::report
