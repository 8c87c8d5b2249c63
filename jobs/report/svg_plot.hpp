#pragma once
// A small headless plot writer: panels of line and point series on linear or
// logarithmic axes, vertical markers and horizontal reference lines, written
// as standalone SVG (no GL context, no fonts to ship). Used by replay reports
// (impedance overlays, parameter distributions); pure string building.
#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace piezo::jobs::report {

enum class Scale { Linear, Log };

struct Series {
  std::string label;         // empty: not in the legend
  std::vector<double> x, y;  // non-finite points (or ≤ 0 on a log axis) break the line
  std::string colour = "#1f77b4";
  double width = 1.5;
  bool dashed = false;
  bool points = false;  // circles instead of a line
};

struct VMarker {  // a vertical line across the panel, e.g. a resonance
  double x = 0;
  std::string colour = "#888888";
};

struct HLine {  // a horizontal reference line, e.g. a median
  double y = 0;
  std::string colour = "#888888";
  bool dashed = true;
  std::string label;
};

struct Panel {
  std::string title, x_label, y_label;
  Scale x_scale = Scale::Linear, y_scale = Scale::Linear;
  std::optional<std::pair<double, double>> x_range, y_range;  // default: the data's
  std::vector<Series> series;
  std::vector<VMarker> markers;
  std::vector<HLine> hlines;
};

struct Figure {
  std::string title;
  int width = 900;
  int panel_height = 300;
  std::vector<Panel> panels;
};

std::string render_svg(const Figure& fig);
// Throws std::runtime_error naming the file when it cannot be written.
void write_svg(const Figure& fig, const std::filesystem::path& file);

// Axis helpers (exposed for the tests and for figure_png.hpp).
// The range an axis spans when the panel gives none: the data's (and, for y,
// the reference lines'), padded.
std::pair<double, double> data_range(const Panel& p, bool x_axis);
std::vector<double> linear_ticks(double lo, double hi, int target = 6);
std::vector<double> log_ticks(double lo, double hi);  // decades; 2 and 5 too over < 2 decades
std::string tick_label(double v, Scale s);
std::string xml_escape(const std::string& s);
// Data → pixel along one axis of a panel (both renderers: SVG and PNG).
struct Axis {
  double lo, hi, px0, px1;
  Scale s;
  double to_px(double v) const {
    const double t = s == Scale::Log ? (std::log10(v) - std::log10(lo)) / (std::log10(hi) - std::log10(lo))
                                     : (v - lo) / (hi - lo);
    return px0 + t * (px1 - px0);
  }
};

}  // namespace piezo::jobs::report
