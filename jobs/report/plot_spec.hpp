#pragma once
// One plot description for every front end (issue 42 item 5): a Figure of
// panels, each with its axes (linear or log, labels, ranges), line and point
// series, shaded x bands, filled ±σ areas, vertical markers, horizontal
// reference lines and a note. Toolkit-free: jobs/report/plot_cairo draws it
// as PNG and SVG, ui/gui/plot_widget draws a Panel with ImGui's draw lists
// (zoom, pan, read-out). Axes and ticks: jobs/report/plot_axes.hpp.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace piezo::jobs::report {

enum class Scale { Linear, Log };

// 8-bit RGBA; from "#rrggbb" or "#rrggbbaa" (anything else: grey), so a
// producer may write colours as in CSS.
struct Colour {
  std::uint8_t r = 0, g = 0, b = 0, a = 255;
  constexpr Colour() = default;
  constexpr Colour(std::uint8_t r_, std::uint8_t g_, std::uint8_t b_, std::uint8_t a_ = 255)
      : r(r_), g(g_), b(b_), a(a_) {}
  constexpr Colour(std::string_view hex) {  // NOLINT: implicit, like a CSS colour
    auto nib = [](char c) -> int {
      return c >= '0' && c <= '9' ? c - '0'
             : c >= 'a' && c <= 'f' ? c - 'a' + 10
             : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                    : -1;
    };
    const bool ok = (hex.size() == 7 || hex.size() == 9) && hex[0] == '#';
    int v[4] = {136, 136, 136, 255};
    for (std::size_t k = 0; ok && k < (hex.size() - 1) / 2; ++k) {
      const int hi = nib(hex[1 + 2 * k]), lo = nib(hex[2 + 2 * k]);
      if (hi < 0 || lo < 0) {
        v[0] = v[1] = v[2] = 136, v[3] = 255;
        break;
      }
      v[k] = 16 * hi + lo;
    }
    r = static_cast<std::uint8_t>(v[0]);
    g = static_cast<std::uint8_t>(v[1]);
    b = static_cast<std::uint8_t>(v[2]);
    a = static_cast<std::uint8_t>(v[3]);
  }
  constexpr Colour(const char* hex) : Colour(std::string_view(hex)) {}  // NOLINT
  Colour(const std::string& hex) : Colour(std::string_view(hex)) {}     // NOLINT
  Colour(int) = delete;  // a literal 0 is not a colour (nor a null "#rrggbb")
  bool operator==(const Colour&) const = default;
};

struct Series {
  std::string label{};           // empty: not in the legend
  std::vector<double> x{}, y{};  // non-finite points (or ≤ 0 on a log axis) break the line
  Colour colour{"#1f77b4"};
  double width = 1.5;   // line width, or the radius of a point (at least 2)
  bool dashed = false;
  bool points = false;  // markers instead of a line
  bool listed = true;   // false: not in the legend or the read-out (e.g. the lower half of a ±band)
  // The read-out of sample i on screen (hover and pinned marker); empty: the
  // y value. E.g. the impedance curves: |Z|, phase, R and X.
  std::function<std::string(std::size_t)> readout{};
};

struct VMarker {  // a vertical line across the panel, e.g. a resonance
  double x = 0;
  Colour colour{"#888888"};
  std::string label{};  // heads the on-screen read-out when the cursor snaps to it
  bool snap = false;    // the on-screen read-out cursor jumps to it
};

struct HLine {  // a horizontal reference line, e.g. a median
  double y = 0;
  Colour colour{"#888888"};
  bool dashed = true;
  std::string label{};
};

struct Band {  // a shaded x interval across the panel, e.g. a misfit region
  double x0 = 0, x1 = 0;
  Colour colour{255, 255, 0, 40};
  std::string label{};        // drawn inside the band (upright when it fits, else turned)
  std::string short_label{};  // non-empty: drawn instead of a label that has to be turned
  std::string detail{};  // the on-screen read-out adds it while the cursor is in the band
};

struct Fill {  // the area between two curves on the same x, e.g. ±1σ
  std::string label{};  // empty: not in the legend
  std::vector<double> x{}, y_lo{}, y_hi{};
  Colour colour{150, 150, 150, 110};
};

enum class LegendPlace { TopRight, BottomLeft };

struct Panel {
  std::string title{}, x_label{}, y_label{};
  Scale x_scale = Scale::Linear, y_scale = Scale::Linear;
  std::optional<std::pair<double, double>> x_range{}, y_range{};  // default: the data's
  std::vector<Series> series{};
  std::vector<VMarker> markers{};
  std::vector<HLine> hlines{};
  std::vector<Band> bands{};
  std::vector<Fill> fills{};
  std::string note{};  // top right inside the panel, e.g. "clipped at ±3 dB"
  LegendPlace legend = LegendPlace::TopRight;
  std::string x_unit{}, y_unit{};  // non-empty: tick labels carry it ("20 kHz" rather than "20k")
  double height_weight = 1;        // share of the figure's height (stacked panels)
  // How an interactive view opens (issue 41 item 5): an x range to open on
  // (e.g. |Z| on the resonance band; a double-click still fits all), the y
  // range then from the samples inside it; and a y range from the quantiles
  // [q, 1 - q] of those samples, so a few points at the edges do not flatten
  // the rest (0: the full range). The files show x_range / y_range.
  double fit_x0 = 0, fit_x1 = 0;  // fit_x1 > fit_x0: open on [fit_x0, fit_x1]
  double fit_y_quantile = 0;
};

struct Figure {
  std::string title{};
  std::string subtitle{};  // a line under the title (cut to the width)
  std::string note{};      // a muted line under it, e.g. a verdict's numbers
  int width = 900;
  int panel_height = 300;  // per panel, when `height` is 0
  int height = 0;          // > 0: the whole figure, shared by the panels' height_weight
  // Panels stacked on one x axis: tick labels and the x label under the last only.
  bool shared_x = false;
  std::vector<Panel> panels{};
};

}  // namespace piezo::jobs::report
