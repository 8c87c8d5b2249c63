#pragma once
// A Figure of svg_plot.hpp drawn as a PNG on a PngCanvas (png_canvas.hpp):
// the same panels, axes, ticks, series, markers, reference lines and legends
// as render_svg, so a report can ship the same plot in both formats (the lot
// report's histograms). Headless; no GL context.
#include <filesystem>

#include "jobs/report/png_canvas.hpp"
#include "jobs/report/svg_plot.hpp"

namespace piezo::jobs::report {

// "#rrggbb" → Rgba (opaque); anything else → grey.
Rgba parse_colour(const std::string& hex);

PngCanvas render_png(const Figure& fig);
// Throws std::runtime_error naming the file when it cannot be written.
void write_png(const Figure& fig, const std::filesystem::path& file);

}  // namespace piezo::jobs::report
