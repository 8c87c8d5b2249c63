#pragma once
// The plot description (plot_spec.hpp) drawn by Cairo: one drawing routine,
// onto an image surface for PNG and onto an SVG surface for SVG, so both
// files of a plot show the same thing. Headless (no X, no GL context); text
// by Cairo's toy API in the generic "sans-serif" family (fontconfig picks
// the face). The GUI draws the same description with ImGui
// (ui/gui/plot_widget.hpp).
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "jobs/report/plot_spec.hpp"

namespace piezo::jobs::report {

struct PixelRect {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

// Where a figure's parts lie, in pixels: its size and each panel's plot area
// (inside the axes), top to bottom.
struct FigureLayout {
  int width = 0, height = 0;
  std::vector<PixelRect> plots;
};
FigureLayout layout_figure(const Figure& fig);

// A drawn figure's pixels: RGBA, 4 bytes per pixel, rows top-down.
struct Raster {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;
  Colour pixel(int x, int y) const;  // throws std::out_of_range outside
};
Raster render_raster(const Figure& fig);
std::string render_svg(const Figure& fig);

// Both throw std::runtime_error naming the file when it cannot be written.
void write_png(const Figure& fig, const std::filesystem::path& file);
void write_svg(const Figure& fig, const std::filesystem::path& file);

}  // namespace piezo::jobs::report
