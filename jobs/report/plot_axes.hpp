#pragma once
// Axes of a plot description (plot_spec.hpp), shared by the Cairo renderer
// (plot_cairo.hpp) and the GUI's plot widget: data → pixel maps on linear and
// log axes, the ranges a panel spans when it gives none, the tick positions
// for an axis of a given length in pixels, and the tick labels.
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "jobs/report/plot_spec.hpp"

namespace piezo::jobs::report {

// A value an axis can show: finite, and > 0 on a log axis.
inline bool usable(double v, Scale s) { return std::isfinite(v) && (s == Scale::Linear || v > 0); }

// Data → pixel along one axis ([lo, hi] onto [px0, px1]; px1 < px0 for a y axis).
struct AxisMap {
  double lo = 0, hi = 1, px0 = 0, px1 = 1;
  Scale s = Scale::Linear;
  double fwd(double v) const { return s == Scale::Log ? std::log10(v) : v; }
  double to_px(double v) const {
    if (!usable(v, s)) return NAN;
    return px0 + (fwd(v) - fwd(lo)) / (fwd(hi) - fwd(lo)) * (px1 - px0);
  }
  double from_px(double p) const {
    const double t = fwd(lo) + (p - px0) / (px1 - px0) * (fwd(hi) - fwd(lo));
    return s == Scale::Log ? std::pow(10.0, t) : t;
  }
};

// The range an axis spans when the panel gives none: the data's (and, for y,
// the reference lines' and the fills'), padded.
std::pair<double, double> data_range(const Panel& p, bool x_axis);

// The view an interactive plot opens on (Panel::fit_x0/fit_x1/fit_y_quantile);
// `all`: every sample, unpadded in x, 5 % padding in y (log: of the decades).
struct ViewRange {
  double x0, x1, y0, y1;
};
ViewRange fit_range(const Panel& p, bool all = false);

std::vector<double> linear_ticks(double lo, double hi, int target = 6);
// Decades; with 2 and 5 between them when `fine`.
std::vector<double> log_ticks(double lo, double hi, bool fine);
// Every integer multiple of each decade (a log axis' minor grid).
std::vector<double> log_minor_ticks(double lo, double hi);

// The labelled ticks and the grid-only ones of an axis `length_px` long with
// labels about `label_px` wide (along the axis) each: as many round values as
// fit; a log axis by every multiple of a decade, 1-2-5, 1-3 or decades,
// the finest that fits (the minor grid: every multiple).
struct AxisTicks {
  std::vector<double> major, minor;
};
AxisTicks axis_ticks(double lo, double hi, Scale s, double length_px, double label_px);

// "1k", "20k", "2M" on a log axis (SI prefixes), "%.6g" on a linear one;
// with a unit: "20 kHz", "0.5 dB".
std::string tick_label(double v, Scale s, const std::string& unit = {});

}  // namespace piezo::jobs::report
