#pragma once
// A small plot widget on ImGui's draw lists (no plotting library is packaged
// for ImGui on Debian) that draws the reports' plot description
// (jobs/report/plot_spec.hpp, axes and ticks from plot_axes.hpp): linear or
// logarithmic axes, several series, vertical markers, shaded bands,
// mouse-wheel zoom, drag to pan, double-click to fit,
// a hover read-out that snaps to the markers that ask for it (resonances), a
// read-out pinned by a right click, and a legend. The view state lives in PlotView (owned by
// the caller's window state, not in function statics).
#include <imgui.h>

#include <complex>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "jobs/report/plot_spec.hpp"

namespace piezo::gui {

// The plot description is the reports' (jobs/report/plot_spec.hpp): a panel
// with its series, markers (`snap`: the read-out cursor jumps to it within
// kSnapPixels), shaded bands (`detail` joins the hover read-out inside the
// band) and the view it opens on; here only the view state is the GUI's own.
using PlotSpec = jobs::report::Panel;
using Series = jobs::report::Series;
using Marker = jobs::report::VMarker;
using Band = jobs::report::Band;
using jobs::report::Colour;
using jobs::report::Scale;
inline constexpr float kSnapPixels = 8.0f;

inline ImU32 im_colour(Colour c) { return IM_COL32(c.r, c.g, c.b, c.a); }
inline constexpr Colour colour_of(ImU32 c) {
  return {static_cast<std::uint8_t>(c >> IM_COL32_R_SHIFT), static_cast<std::uint8_t>(c >> IM_COL32_G_SHIFT),
          static_cast<std::uint8_t>(c >> IM_COL32_B_SHIFT), static_cast<std::uint8_t>(c >> IM_COL32_A_SHIFT)};
}

struct PlotView {
  double x0 = 1, x1 = 10, y0 = 0, y1 = 1;  // visible range (data units)
  bool fitted = false;                     // fit to data on the next draw
  ImVec4 frame{0, 0, 0, 0};  // where plot() drew the data area last (x0, y0, x1, y1; screen pixels)
  // A read-out pinned by a right click (snapped like the hover one); a right
  // click near it removes it.
  std::optional<double> pinned{};
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
// (A series is read only where its x rises: the look-up is by x.)
std::vector<std::pair<ImU32, std::string>> readout_at(const PlotSpec& spec, double x, const Marker* snapped);

}  // namespace piezo::gui
