#include "jobs/report/figure_png.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace piezo::jobs::report {

namespace {

// The margins of svg_plot.cpp's panels, so both formats lay out alike.
constexpr double kLeft = 78, kRight = 24, kTop = 30, kBottom = 44;
constexpr Rgba kInk{30, 30, 30, 255}, kGrid{228, 228, 228, 255}, kFrame{51, 51, 51, 255},
    kLabel{85, 85, 85, 255};

bool usable(double v, Scale s) { return std::isfinite(v) && (s == Scale::Linear || v > 0); }

void render_panel(PngCanvas& c, const Panel& p, double x0, double y0, double w, double h) {
  const auto xr = p.x_range.value_or(data_range(p, true));
  const auto yr = p.y_range.value_or(data_range(p, false));
  const Axis ax{xr.first, xr.second, x0 + kLeft, x0 + w - kRight, p.x_scale};
  const Axis ay{yr.first, yr.second, y0 + h - kBottom, y0 + kTop, p.y_scale};
  c.fill_rect(ax.px0, ay.px1, ax.px1, ay.px0, {255, 255, 255, 255});
  const auto xt = p.x_scale == Scale::Log ? log_ticks(ax.lo, ax.hi) : linear_ticks(ax.lo, ax.hi);
  const auto yt = p.y_scale == Scale::Log ? log_ticks(ay.lo, ay.hi) : linear_ticks(ay.lo, ay.hi);
  for (double t : xt) {
    const double x = ax.to_px(t);
    c.line({x, ay.px1}, {x, ay.px0}, kGrid);
    c.text(x, ay.px0 + 4, tick_label(t, p.x_scale), kInk, FontSize::Normal, Align::Centre);
  }
  for (double t : yt) {
    const double y = ay.to_px(t);
    c.line({ax.px0, y}, {ax.px1, y}, kGrid);
    c.text(ax.px0 - 6, y - c.line_height() / 2, tick_label(t, p.y_scale), kInk, FontSize::Normal,
           Align::Right);
  }
  c.text(x0 + w / 2, y0 + 6, p.title, kInk, FontSize::Normal, Align::Centre);
  c.text((ax.px0 + ax.px1) / 2, ay.px0 + 22, p.x_label, kInk, FontSize::Normal, Align::Centre);
  c.text(x0 + 6, (ay.px0 + ay.px1) / 2 + c.text_width(p.y_label) / 2, p.y_label, kInk,
         FontSize::Normal, Align::Left, /*vertical=*/true);
  c.set_clip(ax.px0, ay.px1, ax.px1, ay.px0);
  for (const auto& m : p.markers)
    if (usable(m.x, p.x_scale)) {
      const double x = ax.to_px(m.x);
      c.polyline({{x, ay.px1}, {x, ay.px0}}, parse_colour(m.colour), 1.0, 3.0);
    }
  for (const auto& hl : p.hlines)
    if (usable(hl.y, p.y_scale)) {
      const double y = ay.to_px(hl.y);
      c.polyline({{ax.px0, y}, {ax.px1, y}}, parse_colour(hl.colour), 1.0, hl.dashed ? 5.0 : 0.0);
      if (!hl.label.empty())
        c.text(ax.px1 - 4, y - 4 - c.line_height(), hl.label, kLabel, FontSize::Normal,
               Align::Right);
    }
  for (const auto& s : p.series) {
    const std::size_t n = std::min(s.x.size(), s.y.size());
    const Rgba col = parse_colour(s.colour);
    if (s.points) {
      const double r = std::max(2.0, s.width);
      for (std::size_t i = 0; i < n; ++i)
        if (usable(s.x[i], p.x_scale) && usable(s.y[i], p.y_scale)) {
          const double x = ax.to_px(s.x[i]), y = ay.to_px(s.y[i]);
          c.fill_rect(x - r, y - r, x + r, y + r, col);
        }
      continue;
    }
    std::vector<Point> pts;
    for (std::size_t i = 0; i < n; ++i)
      pts.push_back(usable(s.x[i], p.x_scale) && usable(s.y[i], p.y_scale)
                        ? Point{ax.to_px(s.x[i]), ay.to_px(s.y[i])}
                        : Point{NAN, NAN});
    c.polyline(pts, col, s.width, s.dashed ? 6.0 : 0.0);
  }
  c.reset_clip();
  c.fill_rect(ax.px0, ay.px1, ax.px1, ay.px1 + 1, kFrame);
  c.fill_rect(ax.px0, ay.px0 - 1, ax.px1, ay.px0, kFrame);
  c.fill_rect(ax.px0, ay.px1, ax.px0 + 1, ay.px0, kFrame);
  c.fill_rect(ax.px1 - 1, ay.px1, ax.px1, ay.px0, kFrame);
  std::size_t entries = 0;
  for (const auto& s : p.series) entries += !s.label.empty();
  if (!entries) return;
  const double lw = 192, lh = 15.0 * static_cast<double>(entries) + 6;
  c.fill_rect(ax.px1 - lw - 4, ay.px1 + 3, ax.px1 - 4, ay.px1 + 3 + lh, {255, 255, 255, 220});
  double ly = ay.px1 + 6;
  for (const auto& s : p.series) {
    if (s.label.empty()) continue;
    const double lx = ax.px1 - lw;
    const Rgba col = parse_colour(s.colour);
    if (s.points)
      c.fill_rect(lx + 8, ly + 3, lx + 14, ly + 9, col);
    else
      c.polyline({{lx, ly + 6}, {lx + 22, ly + 6}}, col, std::min(s.width, 4.0),
                 s.dashed ? 6.0 : 0.0);
    c.text(lx + 28, ly, s.label, kInk);
    ly += 15;
  }
}

}  // namespace

Rgba parse_colour(const std::string& hex) {
  if (hex.size() != 7 || hex[0] != '#') return {136, 136, 136, 255};
  auto byte = [&](int i) {
    return static_cast<std::uint8_t>(std::strtol(hex.substr(1 + 2 * i, 2).c_str(), nullptr, 16));
  };
  return {byte(0), byte(1), byte(2), 255};
}

PngCanvas render_png(const Figure& fig) {
  const double title_h = fig.title.empty() ? 0 : 28;
  const int h = static_cast<int>(
      std::ceil(title_h + fig.panel_height * static_cast<double>(fig.panels.size())));
  PngCanvas c(fig.width, std::max(1, h), {250, 250, 250, 255});
  if (!fig.title.empty())
    c.text(fig.width / 2.0, 6, fig.title, kInk, FontSize::Normal, Align::Centre);
  for (std::size_t k = 0; k < fig.panels.size(); ++k)
    render_panel(c, fig.panels[k], 0, title_h + fig.panel_height * static_cast<double>(k),
                 fig.width, fig.panel_height);
  return c;
}

void write_png(const Figure& fig, const std::filesystem::path& file) {
  render_png(fig).save_png(file);
}

}  // namespace piezo::jobs::report
