#pragma once
// A small plot widget on ImGui's draw lists (no plotting library is packaged
// for ImGui on Debian): linear or logarithmic axes, several series, vertical
// markers, shaded bands, mouse-wheel zoom, drag to pan, double-click to fit,
// a hover read-out and a legend. The view state lives in PlotView (owned by
// the caller's window state, not in function statics).
#include <imgui.h>

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
};

struct Marker {
  double x = 0;
  ImU32 color = IM_COL32(255, 255, 255, 120);
};

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
};

struct PlotSpec {
  std::string title, x_label, y_label;
  std::vector<Series> series;
  std::vector<Marker> markers;
  std::vector<Band> bands;
};

// Draws the plot in a child region of `size`; returns true while hovered.
bool plot(const char* id, const PlotSpec& spec, PlotView& view, ImVec2 size);

// Fit the view to the data (used by plot() when !view.fitted).
void fit_view(const PlotSpec& spec, PlotView& view);

}  // namespace piezo::gui
