#pragma once
// A small plot widget on ImGui's draw lists (no plotting library is packaged
// for ImGui on Debian): linear or logarithmic axes, several series, vertical
// markers, shaded bands, mouse-wheel zoom, drag to pan, double-click to fit,
// a hover read-out that snaps to the markers that ask for it (resonances), a
// read-out pinned by a right click, and a legend. The view state lives in PlotView (owned by
// the caller's window state, not in function statics).
#include <imgui.h>

#include <complex>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace piezo::gui {

struct Series {
  std::string label;
  std::vector<double> x, y;
  ImU32 color = IM_COL32(255, 255, 255, 255);
  float thickness = 1.5f;
  bool points = false;  // draw markers instead of a line
  bool listed =
      true;  // in the legend and the hover read-out (false: e.g. the lower half of a ±band)
  // The read-out of sample i (hover and pinned marker); empty: the y value.
  // E.g. the impedance curves: |Z|, phase, R and X.
  std::function<std::string(std::size_t)> readout{};
  bool hover = true;  // in the hover read-out (which looks samples up by x: x must rise)
};

struct Marker {
  double x = 0;
  ImU32 color = IM_COL32(255, 255, 255, 120);
  std::string label{};  // heads the read-out when the cursor snaps to it (e.g. "fr 51.59 kHz")
  bool snap = false;  // the read-out cursor jumps to it within kSnapPixels
};
inline constexpr float kSnapPixels = 8.0f;

struct Band {
  double x0 = 0, x1 = 0;
  ImU32 color = IM_COL32(255, 255, 0, 40);
  std::string label;   // drawn inside the band when it fits
  std::string detail;  // added to the hover read-out while the cursor is in the band
};

struct PlotView {
  bool log_x = true, log_y = false;
  double x0 = 1, x1 = 10, y0 = 0, y1 = 1;  // visible range (data units)
  bool fitted = false;                     // fit to data on the next draw
  ImVec4 frame{0, 0, 0, 0};  // where plot() drew the data area last (x0, y0, x1, y1; screen pixels)
  // A read-out pinned by a right click (snapped like the hover one); a right
  // click near it removes it.
  std::optional<double> pinned{};
};

struct PlotSpec {
  std::string title, x_label, y_label;
  std::vector<Series> series;
  std::vector<Marker> markers;
  std::vector<Band> bands;
  // How fit_view frames the data (issue 41 item 5): an x range to open on
  // (e.g. |Z| on the resonance band; double-click still fits), the y range
  // then from the samples inside it; and a y range from the quantiles
  // [q, 1 - q] of those samples, so a few points at the band's edges do not
  // flatten the rest (0: the full range).
  double fit_x0 = 0, fit_x1 = 0;  // fit_x1 > fit_x0: open on [fit_x0, fit_x1]
  double fit_y_quantile = 0;
};

// Draws the plot in a child region of `size`; returns true while hovered.
bool plot(const char* id, const PlotSpec& spec, PlotView& view, ImVec2 size);

// Fit the view to the data (used by plot() when !view.fitted), framed as
// the spec's fit_x0/fit_x1 and fit_y_quantile ask; `all`: every sample (the
// double-click).
void fit_view(const PlotSpec& spec, PlotView& view, bool all = false);

// The snapping marker nearest to the cursor at screen x `mouse_px` within
// `radius_px`, `to_px` mapping data x to screen x; nullptr when none.
const Marker* snap_marker(const std::vector<Marker>& markers, float mouse_px,
                          const std::function<float(double)>& to_px, float radius_px = kSnapPixels);

// "|Z| 1.23 kohm  phase -45.1 deg  R 869 ohm  X -869 ohm" (the marker read-out
// of an impedance curve; ASCII units: ImGui's default font has no omega).
std::string impedance_readout(std::complex<double> z);

// The read-out lines at data x: the marker's label (when snapped) and each
// listed series' nearest sample inside its own x range.
std::vector<std::pair<ImU32, std::string>> readout_at(const PlotSpec& spec, double x, const Marker* snapped);

}  // namespace piezo::gui
