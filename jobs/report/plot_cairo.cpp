// The Cairo renderer of the plot description (see plot_cairo.hpp). One
// routine, draw_figure(), draws on whatever surface it is handed: an ARGB32
// image for PNG files and pixel checks, an SVG stream for SVG files.
#include "jobs/report/plot_cairo.hpp"

#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <utility>

#include "jobs/report/plot_axes.hpp"

namespace piezo::jobs::report {

namespace {

// Panel margins around the plot area (the tick labels and axis labels live there).
constexpr double kLeft = 78, kRight = 24, kTitleTop = 30, kTop = 12, kBottom = 44, kGap = 12;
constexpr double kTitleH = 30, kLineH = 18;  // the figure's title, then its subtitle and note lines
const Colour kBackground{250, 250, 250}, kPlotBg{255, 255, 255}, kInk{35, 35, 35}, kMuted{95, 95, 95},
    kGrid{0, 0, 0, 30}, kMinorGrid{0, 0, 0, 14}, kFrame{51, 51, 51}, kHalo{255, 255, 255, 210};
constexpr double kTickFont = 11, kLabelFont = 12, kTitleFont = 13, kFigTitleFont = 18;

using CairoPtr = std::unique_ptr<cairo_t, decltype(&cairo_destroy)>;
using SurfacePtr = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;

double header_height(const Figure& f) {
  return (f.title.empty() ? 0 : kTitleH) + (f.subtitle.empty() ? 0 : kLineH) + (f.note.empty() ? 0 : kLineH) +
         (f.title.empty() && f.subtitle.empty() && f.note.empty() ? 0 : 4);
}

void colour(cairo_t* cr, Colour c) { cairo_set_source_rgba(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0, c.a / 255.0); }

void font(cairo_t* cr, double size, bool bold = false) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
}

double text_width(cairo_t* cr, const std::string& s) {
  cairo_text_extents_t e;
  cairo_text_extents(cr, s.c_str(), &e);
  return e.x_advance;
}

// `s` cut to `max_w` (current font), ending in "..." when cut (whole code points only).
std::string fit_width(cairo_t* cr, const std::string& s, double max_w) {
  if (text_width(cr, s) <= max_w) return s;
  std::string t = s;
  while (!t.empty() && text_width(cr, t + "...") > max_w) {
    t.pop_back();
    while (!t.empty() && (static_cast<unsigned char>(t.back()) & 0xC0) == 0x80) t.pop_back();  // continuation
    if (!t.empty() && static_cast<unsigned char>(t.back()) >= 0xC0) t.pop_back();               // lead byte
  }
  return t + "...";
}

enum class Align { Left, Centre, Right };

// Text with its baseline at y (upright), or turned to read upwards with its
// baseline at x (`vertical`); `halo`: on a white outline, readable over curves.
void text(cairo_t* cr, double x, double y, const std::string& s, Colour c, Align al = Align::Left,
          bool vertical = false, bool halo = false) {
  if (s.empty()) return;
  const double w = text_width(cr, s);
  const double shift = al == Align::Left ? 0.0 : al == Align::Centre ? w / 2 : w;
  cairo_save(cr);
  cairo_translate(cr, x, y);
  if (vertical) cairo_rotate(cr, -M_PI / 2);
  cairo_move_to(cr, -shift, 0);
  if (halo) {
    cairo_text_path(cr, s.c_str());
    colour(cr, kHalo);
    cairo_set_line_width(cr, 3.0);
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
    cairo_stroke_preserve(cr);
    colour(cr, c);
    cairo_fill(cr);
  } else {
    colour(cr, c);
    cairo_show_text(cr, s.c_str());
  }
  cairo_restore(cr);
}

void line(cairo_t* cr, double x0, double y0, double x1, double y1, Colour c, double width = 1.0,
          double dash = 0.0) {
  cairo_move_to(cr, x0, y0);
  cairo_line_to(cr, x1, y1);
  colour(cr, c);
  cairo_set_line_width(cr, width);
  if (dash > 0) {
    const double d[] = {dash, dash};
    cairo_set_dash(cr, d, 2, 0);
  }
  cairo_stroke(cr);
  cairo_set_dash(cr, nullptr, 0, 0);
}

// A crisp one-pixel line on the pixel grid (grid lines, ticks).
double crisp(double v) { return std::round(v) + 0.5; }

struct PanelBox {
  PixelRect plot;  // inside the axes
  double cell_x0, cell_y0, cell_x1;
  bool x_labels;  // tick labels and the x label under it
};

std::vector<PanelBox> boxes(const Figure& f, int& height) {
  std::vector<PanelBox> out;
  const double head = header_height(f);
  double total_w = 0;
  for (const auto& p : f.panels) total_w += p.height_weight > 0 ? p.height_weight : 1.0;
  const double avail = f.height > 0 ? f.height - head : f.panel_height * static_cast<double>(f.panels.size());
  height = f.height > 0 ? f.height : static_cast<int>(std::ceil(head + avail));
  double y = head;
  for (std::size_t k = 0; k < f.panels.size(); ++k) {
    const Panel& p = f.panels[k];
    const double w = p.height_weight > 0 ? p.height_weight : 1.0;
    const double h = f.height > 0 ? std::round(avail * w / total_w) : f.panel_height;
    const bool last = k + 1 == f.panels.size();
    const bool labels = !f.shared_x || last;
    const double top = p.title.empty() ? kTop : kTitleTop, bottom = labels ? kBottom : kGap;
    out.push_back({{kLeft, y + top, f.width - kRight, y + h - bottom}, 0, y, static_cast<double>(f.width), labels});
    y += h;
  }
  if (f.height > 0 && !out.empty()) out.back().plot.y1 = f.height - kBottom;  // rounding: the last one ends the figure
  return out;
}

struct Axes {
  AxisMap x, y;
};

Axes axes_of(const Panel& p, const PixelRect& r) {
  const auto xr = p.x_range.value_or(data_range(p, true));
  const auto yr = p.y_range.value_or(data_range(p, false));
  return {{xr.first, xr.second, r.x0, r.x1, p.x_scale}, {yr.first, yr.second, r.y1, r.y0, p.y_scale}};
}

void grid_and_ticks(cairo_t* cr, const Panel& p, const PixelRect& r, const Axes& a, bool x_labels) {
  font(cr, kTickFont);
  const double label_w = text_width(cr, tick_label(a.x.hi, p.x_scale, p.x_unit)) + 6;
  const auto xt = axis_ticks(a.x.lo, a.x.hi, p.x_scale, r.x1 - r.x0, label_w);
  const auto yt = axis_ticks(a.y.lo, a.y.hi, p.y_scale, r.y1 - r.y0, kTickFont + 4);
  for (double t : xt.minor) line(cr, crisp(a.x.to_px(t)), r.y0, crisp(a.x.to_px(t)), r.y1, kMinorGrid);
  for (double t : yt.minor) line(cr, r.x0, crisp(a.y.to_px(t)), r.x1, crisp(a.y.to_px(t)), kMinorGrid);
  for (double t : xt.major) {
    const double x = crisp(a.x.to_px(t));
    line(cr, x, r.y0, x, r.y1, kGrid);
    line(cr, x, r.y1, x, r.y1 + 4, kMuted);
    if (x_labels) text(cr, a.x.to_px(t), r.y1 + 16, tick_label(t, p.x_scale, p.x_unit), kInk, Align::Centre);
  }
  for (double t : yt.major) {
    const double y = crisp(a.y.to_px(t));
    line(cr, r.x0, y, r.x1, y, kGrid);
    line(cr, r.x0 - 4, y, r.x0, y, kMuted);
    text(cr, r.x0 - 6, a.y.to_px(t) + 4, tick_label(t, p.y_scale, p.y_unit), kInk, Align::Right);
  }
}

void series_path(cairo_t* cr, const Series& s, const Axes& a) {
  bool pen = false;
  for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
    if (!usable(s.x[i], a.x.s) || !usable(s.y[i], a.y.s)) {
      pen = false;
      continue;
    }
    const double x = a.x.to_px(s.x[i]), y = a.y.to_px(s.y[i]);
    if (pen)
      cairo_line_to(cr, x, y);
    else
      cairo_move_to(cr, x, y);
    pen = true;
  }
}

void draw_series(cairo_t* cr, const Series& s, const Axes& a) {
  colour(cr, s.colour);
  if (s.points) {
    const double rad = std::max(2.0, s.width);
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i)
      if (usable(s.x[i], a.x.s) && usable(s.y[i], a.y.s)) {
        cairo_new_sub_path(cr);
        cairo_arc(cr, a.x.to_px(s.x[i]), a.y.to_px(s.y[i]), rad, 0, 2 * M_PI);
      }
    cairo_fill(cr);
    return;
  }
  series_path(cr, s, a);
  cairo_set_line_width(cr, s.width);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
  if (s.dashed) {
    const double d[] = {7, 4};
    cairo_set_dash(cr, d, 2, 0);
  }
  cairo_stroke(cr);
  cairo_set_dash(cr, nullptr, 0, 0);
}

void draw_fill(cairo_t* cr, const Fill& f, const Axes& a) {
  // Runs of usable samples, each closed along y_hi forwards and y_lo back.
  const std::size_t n = std::min({f.x.size(), f.y_lo.size(), f.y_hi.size()});
  auto ok = [&](std::size_t i) { return usable(f.x[i], a.x.s) && usable(f.y_lo[i], a.y.s) && usable(f.y_hi[i], a.y.s); };
  for (std::size_t i = 0; i < n;) {
    if (!ok(i)) {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j < n && ok(j)) ++j;
    cairo_move_to(cr, a.x.to_px(f.x[i]), a.y.to_px(f.y_hi[i]));
    for (std::size_t k = i + 1; k < j; ++k) cairo_line_to(cr, a.x.to_px(f.x[k]), a.y.to_px(f.y_hi[k]));
    for (std::size_t k = j; k-- > i;) cairo_line_to(cr, a.x.to_px(f.x[k]), a.y.to_px(f.y_lo[k]));
    cairo_close_path(cr);
    i = j;
  }
  colour(cr, f.colour);
  cairo_fill(cr);
}

// Band labels along the top of the plot, on a halo (they may cross a curve):
// upright in a band wide enough, else turned, in x order at least a line
// apart (nudged off narrow neighbouring bands, never dropped).
void band_labels(cairo_t* cr, const Panel& p, const PixelRect& r, const Axes& a) {
  font(cr, kLabelFont);
  const double lh = kLabelFont + 3;
  struct Label {
    double x;
    bool flat;
    const std::string* s;
  };
  std::vector<Label> ls;
  for (const auto& b : p.bands) {
    if (b.label.empty()) continue;
    const double xa = std::clamp(a.x.to_px(std::min(b.x0, b.x1)), r.x0, r.x1);
    const double xz = std::clamp(a.x.to_px(std::max(b.x0, b.x1)), r.x0, r.x1);
    if (!(xz > xa)) continue;
    const bool flat = xz - xa > text_width(cr, b.label) + 12;
    const std::string& s = flat || b.short_label.empty() ? b.label : b.short_label;
    ls.push_back({flat ? (xa + xz) / 2 : std::round((xa + xz) / 2 + lh / 2 - 3), flat, &s});
  }
  for (std::size_t k = 1; k < ls.size(); ++k)  // left to right: keep a line apart
    if (!ls[k].flat && !ls[k - 1].flat) ls[k].x = std::max(ls[k].x, ls[k - 1].x + lh + 1);
  for (std::size_t k = ls.size(); k-- > 0;) {  // right to left: stay inside the panel
    if (ls[k].flat) continue;
    ls[k].x = std::min(ls[k].x, r.x1 - 4);
    if (k + 1 < ls.size() && !ls[k + 1].flat) ls[k].x = std::min(ls[k].x, ls[k + 1].x - lh - 1);
  }
  cairo_save(cr);
  cairo_rectangle(cr, r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0);  // a long label on a short panel is cut
  cairo_clip(cr);
  for (const auto& l : ls) {
    if (l.flat)
      text(cr, l.x, r.y0 + 6 + kLabelFont, *l.s, kInk, Align::Centre, false, true);
    else
      text(cr, l.x, r.y0 + 6 + text_width(cr, *l.s), *l.s, kInk, Align::Left, true, true);
  }
  cairo_restore(cr);
}

void legend(cairo_t* cr, const Panel& p, const PixelRect& r) {
  struct Entry {
    const std::string* label;
    const Series* s;
    const Fill* f;
  };
  std::vector<Entry> es;
  for (const auto& s : p.series)
    if (s.listed && !s.label.empty()) es.push_back({&s.label, &s, nullptr});
  for (const auto& f : p.fills)
    if (!f.label.empty()) es.push_back({&f.label, nullptr, &f});
  if (es.empty()) return;
  font(cr, kTickFont);
  double w = 0;
  for (const auto& e : es) w = std::max(w, text_width(cr, *e.label));
  const double lh = 15, bw = std::min(w + 40, r.x1 - r.x0 - 8), bh = lh * static_cast<double>(es.size()) + 6;
  const double x0 = p.legend == LegendPlace::TopRight ? r.x1 - bw - 4 : r.x0 + 8;
  const double y0 = p.legend == LegendPlace::TopRight ? r.y0 + 4 : r.y1 - bh - 8;
  cairo_rectangle(cr, x0 + 0.5, y0 + 0.5, bw, bh);
  colour(cr, {255, 255, 255, 220});
  cairo_fill_preserve(cr);
  colour(cr, {204, 204, 204});
  cairo_set_line_width(cr, 1);
  cairo_stroke(cr);
  double y = y0 + 3 + lh / 2;
  for (const auto& e : es) {
    const double sx = x0 + 6;
    if (e.f) {
      cairo_rectangle(cr, sx, y - 5, 22, 10);
      colour(cr, e.f->colour);
      cairo_fill(cr);
    } else if (e.s->points) {
      cairo_arc(cr, sx + 11, y, 3, 0, 2 * M_PI);
      colour(cr, e.s->colour);
      cairo_fill(cr);
    } else {
      line(cr, sx, y, sx + 22, y, e.s->colour, std::min(e.s->width, 4.0), e.s->dashed ? 5.0 : 0.0);
    }
    text(cr, sx + 28, y + 4, fit_width(cr, *e.label, bw - 36), kInk);
    y += lh;
  }
}

void draw_panel(cairo_t* cr, const Panel& p, const PanelBox& box) {
  const PixelRect& r = box.plot;
  if (!(r.x1 > r.x0 && r.y1 > r.y0)) return;
  const Axes a = axes_of(p, r);
  cairo_rectangle(cr, r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0);
  colour(cr, kPlotBg);
  cairo_fill(cr);
  cairo_save(cr);
  cairo_rectangle(cr, r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0);
  cairo_clip(cr);
  for (const auto& b : p.bands) {
    const double xa = a.x.to_px(b.x0), xz = a.x.to_px(b.x1);
    if (!std::isfinite(xa) || !std::isfinite(xz)) continue;
    cairo_rectangle(cr, std::min(xa, xz), r.y0, std::abs(xz - xa), r.y1 - r.y0);
    colour(cr, b.colour);
    cairo_fill(cr);
  }
  cairo_restore(cr);
  grid_and_ticks(cr, p, r, a, box.x_labels);
  cairo_save(cr);
  cairo_rectangle(cr, r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0);
  cairo_clip(cr);
  for (const auto& f : p.fills) draw_fill(cr, f, a);
  for (const auto& m : p.markers)
    if (usable(m.x, p.x_scale)) line(cr, a.x.to_px(m.x), r.y0, a.x.to_px(m.x), r.y1, m.colour, 1.0, 3.0);
  font(cr, 10);
  for (const auto& h : p.hlines) {
    if (!usable(h.y, p.y_scale)) continue;
    const double y = a.y.to_px(h.y);
    line(cr, r.x0, y, r.x1, y, h.colour, 1.0, h.dashed ? 5.0 : 0.0);
    // Above the line, or below it when the line runs along the top.
    text(cr, r.x1 - 4, y - 4 < r.y0 + 10 ? y + 12 : y - 4, h.label, {85, 85, 85}, Align::Right);
  }
  for (const auto& s : p.series) draw_series(cr, s, a);
  cairo_restore(cr);
  cairo_rectangle(cr, r.x0 - 0.5, r.y0 - 0.5, r.x1 - r.x0 + 1, r.y1 - r.y0 + 1);
  colour(cr, kFrame);
  cairo_set_line_width(cr, 1);
  cairo_stroke(cr);
  band_labels(cr, p, r, a);
  if (!p.note.empty()) {
    font(cr, kLabelFont);
    text(cr, r.x1 - 6, r.y0 + 4 + kLabelFont, p.note, kInk, Align::Right, false, true);
  }
  // Title over the plot, x label under its tick labels, y label turned at the left.
  font(cr, kTitleFont, true);
  text(cr, (box.cell_x0 + box.cell_x1) / 2, r.y0 - 10, fit_width(cr, p.title, box.cell_x1 - box.cell_x0 - 8), kInk,
       Align::Centre);
  font(cr, kLabelFont);
  if (box.x_labels) text(cr, (r.x0 + r.x1) / 2, r.y1 + 34, p.x_label, kInk, Align::Centre);
  const std::string yl = fit_width(cr, p.y_label, r.y1 - r.y0);
  text(cr, box.cell_x0 + 18, (r.y0 + r.y1) / 2 + text_width(cr, yl) / 2, yl, kInk, Align::Left, true);
  legend(cr, p, r);
}

void draw_figure(cairo_t* cr, const Figure& f) {
  int height = 0;
  const auto bs = boxes(f, height);
  colour(cr, kBackground);
  cairo_paint(cr);
  // Title (smaller when it does not fit), subtitle, note: cut to the width.
  double y = 0;
  if (!f.title.empty()) {
    font(cr, kFigTitleFont, true);
    if (text_width(cr, f.title) + 32 > f.width) font(cr, kTitleFont + 1, true);
    text(cr, f.width / 2.0, y + 22, fit_width(cr, f.title, f.width - 16), kInk, Align::Centre);
    y += kTitleH;
  }
  font(cr, kLabelFont);
  for (const auto& [s, c] : {std::pair(&f.subtitle, kInk), std::pair(&f.note, kMuted)})
    if (!s->empty()) {
      text(cr, f.width / 2.0, y + 13, fit_width(cr, *s, f.width - 32), c, Align::Centre);
      y += kLineH;
    }
  for (std::size_t k = 0; k < f.panels.size(); ++k) draw_panel(cr, f.panels[k], bs[k]);
}

void check(cairo_status_t st, const std::string& what) {
  if (st != CAIRO_STATUS_SUCCESS) throw std::runtime_error(what + ": " + cairo_status_to_string(st));
}

SurfacePtr image_of(const Figure& f) {
  const FigureLayout l = layout_figure(f);
  if (l.width < 1 || l.height < 1 || l.width > 16384 || l.height > 16384)
    throw std::invalid_argument("render_raster: a figure must be 1..16384 pixels on each side");
  SurfacePtr s(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, l.width, l.height), cairo_surface_destroy);
  CairoPtr cr(cairo_create(s.get()), cairo_destroy);
  draw_figure(cr.get(), f);
  check(cairo_status(cr.get()), "render_raster");
  cairo_surface_flush(s.get());
  return s;
}

}  // namespace

FigureLayout layout_figure(const Figure& fig) {
  FigureLayout l;
  l.width = fig.width;
  for (const auto& b : boxes(fig, l.height)) l.plots.push_back(b.plot);
  return l;
}

Colour Raster::pixel(int x, int y) const {
  if (x < 0 || y < 0 || x >= width || y >= height) throw std::out_of_range("Raster::pixel: outside the image");
  const std::size_t i = 4 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x));
  return {rgba[i], rgba[i + 1], rgba[i + 2], rgba[i + 3]};
}

Raster render_raster(const Figure& fig) {
  const SurfacePtr s = image_of(fig);
  Raster r;
  r.width = cairo_image_surface_get_width(s.get());
  r.height = cairo_image_surface_get_height(s.get());
  const int stride = cairo_image_surface_get_stride(s.get());
  const unsigned char* d = cairo_image_surface_get_data(s.get());
  r.rgba.resize(static_cast<std::size_t>(r.width) * static_cast<std::size_t>(r.height) * 4);
  for (int y = 0; y < r.height; ++y)
    for (int x = 0; x < r.width; ++x) {
      // ARGB32: native-endian 32-bit words, premultiplied alpha.
      std::uint32_t v;
      std::memcpy(&v, d + static_cast<std::size_t>(y) * static_cast<std::size_t>(stride) + 4 * static_cast<std::size_t>(x),
                  4);
      const std::uint32_t a = v >> 24;
      auto un = [a](std::uint32_t c) { return static_cast<std::uint8_t>(a ? (c * 255 + a / 2) / a : 0); };
      std::uint8_t* o = &r.rgba[4 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(r.width) + static_cast<std::size_t>(x))];
      o[0] = un((v >> 16) & 0xFF);
      o[1] = un((v >> 8) & 0xFF);
      o[2] = un(v & 0xFF);
      o[3] = static_cast<std::uint8_t>(a);
    }
  return r;
}

std::string render_svg(const Figure& fig) {
  const FigureLayout l = layout_figure(fig);
  std::string out;
  const cairo_write_func_t append = [](void* closure, const unsigned char* data, unsigned int n) {
    static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), n);
    return CAIRO_STATUS_SUCCESS;
  };
  {
    SurfacePtr s(cairo_svg_surface_create_for_stream(append, &out, l.width, l.height), cairo_surface_destroy);
    cairo_svg_surface_set_document_unit(s.get(), CAIRO_SVG_UNIT_PX);
    CairoPtr cr(cairo_create(s.get()), cairo_destroy);
    draw_figure(cr.get(), fig);
    check(cairo_status(cr.get()), "render_svg");
    cairo_surface_finish(s.get());
    check(cairo_surface_status(s.get()), "render_svg");
  }
  return out;
}

void write_png(const Figure& fig, const std::filesystem::path& file) {
  const SurfacePtr s = image_of(fig);
  if (cairo_surface_write_to_png(s.get(), file.string().c_str()) != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error("cannot write the PNG file " + file.string());
}

void write_svg(const Figure& fig, const std::filesystem::path& file) {
  const std::string svg = render_svg(fig);
  std::ofstream f(file, std::ios::binary);
  if (!f || !(f << svg) || !f.flush()) throw std::runtime_error("report: cannot write " + file.string());
}

}  // namespace piezo::jobs::report
