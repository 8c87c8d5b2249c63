// CPU raster canvas (see png_canvas.hpp). Anti-aliasing is by exact area
// coverage for rectangles and bands, and by distance to the segment for lines
// (a 1-pixel ramp at the edge). A polyline is first rasterised into a coverage
// mask (maximum over its segments), then composited once, so joints and
// overlapping segments of one curve do not darken a translucent colour.
#include "jobs/report/png_canvas.hpp"

#include <imgui.h>
#include <stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace piezo::jobs::report {

// The embedded ProggyClean font at two sizes, rasterised into one alpha atlas.
struct PngCanvas::Font {
  ImFontAtlas atlas;
  ImFont* normal = nullptr;
  ImFont* large = nullptr;
  unsigned char* alpha = nullptr;
  int tw = 0, th = 0;

  Font() {
    atlas.Flags |= ImFontAtlasFlags_NoMouseCursors | ImFontAtlasFlags_NoBakedLines;
    // One atlas texel per output pixel (ImGui oversamples a font config it is
    // handed 3x horizontally; the blit below copies texels 1:1), snapped to pixels.
    auto config = [](float px) {
      ImFontConfig c;
      c.SizePixels = px;
      c.OversampleH = c.OversampleV = 1;
      c.PixelSnapH = true;
      return c;
    };
    const ImFontConfig n = config(13.0f);  // ProggyClean's design size: pixel-exact glyphs
    normal = atlas.AddFontDefault(&n);
    const ImFontConfig l = config(26.0f);  // twice the design size: still on the pixel grid
    large = atlas.AddFontDefault(&l);
    atlas.GetTexDataAsAlpha8(&alpha, &tw, &th);
    if (!alpha || !normal || !large || !normal->IsLoaded() || !large->IsLoaded())
      throw std::runtime_error("PngCanvas: the embedded font could not be rasterised");
  }
  const ImFont* get(FontSize s) const { return s == FontSize::Large ? large : normal; }
};

namespace {

// Decodes UTF-8; malformed bytes become U+FFFD (drawn as the font's fallback glyph).
std::vector<unsigned> decode_utf8(std::string_view s) {
  std::vector<unsigned> out;
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    int extra = c < 0x80           ? 0
                : (c >> 5) == 0x6  ? 1
                : (c >> 4) == 0xE  ? 2
                : (c >> 3) == 0x1E ? 3
                                   : -1;
    if (extra < 0 ||
        i + static_cast<std::size_t>(extra) >= s.size()) {  // bad lead byte or cut short
      out.push_back(0xFFFD);
      ++i;
      continue;
    }
    unsigned cp = extra == 0   ? c
                  : extra == 1 ? (c & 0x1Fu)
                  : extra == 2 ? (c & 0x0Fu)
                               : (c & 0x07u);
    bool ok = true;
    for (int k = 1; k <= extra; ++k) {
      const auto cc = static_cast<unsigned char>(s[i + static_cast<std::size_t>(k)]);
      if ((cc & 0xC0) != 0x80) ok = false;
      cp = (cp << 6) | (cc & 0x3Fu);
    }
    out.push_back(ok ? cp : 0xFFFD);
    i += ok ? static_cast<std::size_t>(extra) + 1 : 1;
  }
  return out;
}

// Distance from p to the segment ab.
double segment_distance(double px, double py, const Point& a, const Point& b) {
  const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((px - a.x) * dx + (py - a.y) * dy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(px - (a.x + t * dx), py - (a.y + t * dy));
}

bool finite(const Point& p) { return std::isfinite(p.x) && std::isfinite(p.y); }

}  // namespace

PngCanvas::PngCanvas(int width, int height, Rgba background)
    : w_(width), h_(height), font_(std::make_unique<Font>()) {
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw std::invalid_argument("PngCanvas: size must be 1..16384 pixels on each side");
  px_.resize(static_cast<std::size_t>(w_) * static_cast<std::size_t>(h_) * 4);
  for (std::size_t i = 0; i < px_.size(); i += 4) {
    px_[i] = background.r;
    px_[i + 1] = background.g;
    px_[i + 2] = background.b;
    px_[i + 3] = background.a;
  }
  reset_clip();
}

PngCanvas::~PngCanvas() = default;
PngCanvas::PngCanvas(PngCanvas&&) noexcept = default;
PngCanvas& PngCanvas::operator=(PngCanvas&&) noexcept = default;

Rgba PngCanvas::pixel(int x, int y) const {
  if (x < 0 || y < 0 || x >= w_ || y >= h_)
    throw std::out_of_range("PngCanvas::pixel: outside the canvas");
  const std::size_t i = 4 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(w_) +
                             static_cast<std::size_t>(x));
  return {px_[i], px_[i + 1], px_[i + 2], px_[i + 3]};
}

void PngCanvas::set_clip(double x0, double y0, double x1, double y1) {
  cx0_ = std::max(0.0, std::min(x0, x1));
  cy0_ = std::max(0.0, std::min(y0, y1));
  cx1_ = std::min<double>(w_, std::max(x0, x1));
  cy1_ = std::min<double>(h_, std::max(y0, y1));
}

void PngCanvas::reset_clip() { set_clip(0, 0, w_, h_); }

void PngCanvas::blend(int x, int y, Rgba c, double coverage) {
  if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
  const double cx = x + 0.5, cy = y + 0.5;  // a pixel belongs to the clip when its centre does
  if (cx < cx0_ || cx >= cx1_ || cy < cy0_ || cy >= cy1_) return;
  const double a = std::clamp(coverage, 0.0, 1.0) * c.a / 255.0;
  if (a <= 0) return;
  const std::size_t i = 4 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(w_) +
                             static_cast<std::size_t>(x));
  auto mix = [a](std::uint8_t dst, std::uint8_t src) {
    return static_cast<std::uint8_t>(std::lround(dst + (src - dst) * a));
  };
  px_[i] = mix(px_[i], c.r);
  px_[i + 1] = mix(px_[i + 1], c.g);
  px_[i + 2] = mix(px_[i + 2], c.b);
  px_[i + 3] = static_cast<std::uint8_t>(std::lround(px_[i + 3] + (255 - px_[i + 3]) * a));
}

void PngCanvas::fill_rect(double x0, double y0, double x1, double y1, Rgba c) {
  if (!(std::isfinite(x0) && std::isfinite(y0) && std::isfinite(x1) && std::isfinite(y1))) return;
  if (x1 < x0) std::swap(x0, x1);
  if (y1 < y0) std::swap(y0, y1);
  x0 = std::max(x0, cx0_);
  y0 = std::max(y0, cy0_);
  x1 = std::min(x1, cx1_);
  y1 = std::min(y1, cy1_);
  if (x1 <= x0 || y1 <= y0) return;
  const int i0 = static_cast<int>(std::floor(x0)), i1 = static_cast<int>(std::ceil(x1));
  const int j0 = static_cast<int>(std::floor(y0)), j1 = static_cast<int>(std::ceil(y1));
  for (int j = j0; j < j1; ++j) {
    const double cy = std::min<double>(y1, j + 1) - std::max<double>(y0, j);
    for (int i = i0; i < i1; ++i) {
      const double cx = std::min<double>(x1, i + 1) - std::max<double>(x0, i);
      blend(i, j, c, cx * cy);
    }
  }
}

void PngCanvas::fill_band(const std::vector<double>& x, const std::vector<double>& y_top,
                          const std::vector<double>& y_bottom, Rgba c) {
  if (x.size() != y_top.size() || x.size() != y_bottom.size())
    throw std::invalid_argument("PngCanvas::fill_band: x, y_top and y_bottom differ in length");
  if (x.size() < 2) return;
  std::size_t k = 0;
  const int i0 = std::max(0, static_cast<int>(std::floor(x.front())));
  const int i1 = std::min(w_, static_cast<int>(std::ceil(x.back())));
  for (int i = i0; i < i1; ++i) {
    const double cx = i + 0.5;
    if (cx < x.front() || cx > x.back()) continue;
    while (k + 2 < x.size() && x[k + 1] < cx) ++k;
    const double span = x[k + 1] - x[k], t = span > 0 ? (cx - x[k]) / span : 0.0;
    double top = y_top[k] + t * (y_top[k + 1] - y_top[k]);
    double bottom = y_bottom[k] + t * (y_bottom[k + 1] - y_bottom[k]);
    if (!std::isfinite(top) || !std::isfinite(bottom)) continue;
    if (bottom < top) std::swap(top, bottom);
    top = std::max(top, cy0_);
    bottom = std::min(bottom, cy1_);
    for (int j = static_cast<int>(std::floor(top)); j < static_cast<int>(std::ceil(bottom)); ++j)
      blend(i, j, c, std::min<double>(bottom, j + 1) - std::max<double>(top, j));
  }
}

void PngCanvas::composite(const std::vector<float>& mask, int bx0, int by0, int bw, int bh,
                          Rgba c) {
  for (int j = 0; j < bh; ++j)
    for (int i = 0; i < bw; ++i) {
      const float m = mask[static_cast<std::size_t>(j) * static_cast<std::size_t>(bw) +
                           static_cast<std::size_t>(i)];
      if (m > 0) blend(bx0 + i, by0 + j, c, m);
    }
}

void PngCanvas::line(Point a, Point b, Rgba c, double width) { polyline({a, b}, c, width); }

void PngCanvas::polyline(const std::vector<Point>& pts, Rgba c, double width, double dash) {
  if (pts.size() < 2 || !(width > 0)) return;
  // Segments, cut into dashes when asked; the dash phase runs on across joints.
  std::vector<std::pair<Point, Point>> segs;
  double phase = 0;
  for (std::size_t k = 0; k + 1 < pts.size(); ++k) {
    const Point a = pts[k], b = pts[k + 1];
    if (!finite(a) || !finite(b)) continue;
    if (dash <= 0) {
      segs.emplace_back(a, b);
      continue;
    }
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    double s = 0;
    while (s < len) {
      const double in_period = std::fmod(phase, 2 * dash);
      const bool on = in_period < dash;
      const double step = std::min(len - s, (on ? dash : 2 * dash) - in_period);
      if (on && len > 0) {
        const double t0 = s / len, t1 = (s + step) / len;
        segs.emplace_back(Point{a.x + t0 * (b.x - a.x), a.y + t0 * (b.y - a.y)},
                          Point{a.x + t1 * (b.x - a.x), a.y + t1 * (b.y - a.y)});
      }
      s += step;
      phase += step;
    }
  }
  if (segs.empty()) return;
  // Coverage mask over the clip rectangle (curves of a plot stay inside their panel).
  const double r = width / 2 + 0.5;
  const int bx0 = static_cast<int>(std::floor(cx0_)), by0 = static_cast<int>(std::floor(cy0_));
  const int bw = static_cast<int>(std::ceil(cx1_)) - bx0,
            bh = static_cast<int>(std::ceil(cy1_)) - by0;
  if (bw <= 0 || bh <= 0) return;
  std::vector<float> mask(static_cast<std::size_t>(bw) * static_cast<std::size_t>(bh), 0.0f);
  for (const auto& [a, b] : segs) {
    const int i0 = std::max(bx0, static_cast<int>(std::floor(std::min(a.x, b.x) - r)));
    const int i1 = std::min(bx0 + bw, static_cast<int>(std::ceil(std::max(a.x, b.x) + r)));
    const int j0 = std::max(by0, static_cast<int>(std::floor(std::min(a.y, b.y) - r)));
    const int j1 = std::min(by0 + bh, static_cast<int>(std::ceil(std::max(a.y, b.y) + r)));
    for (int j = j0; j < j1; ++j)
      for (int i = i0; i < i1; ++i) {
        const double d = segment_distance(i + 0.5, j + 0.5, a, b);
        // Thinner than a pixel: the full ramp, scaled by the width (keeps hairlines light).
        const double cov = std::clamp(r - d, 0.0, 1.0) * std::min(1.0, width);
        float& m = mask[static_cast<std::size_t>(j - by0) * static_cast<std::size_t>(bw) +
                        static_cast<std::size_t>(i - bx0)];
        m = std::max(m, static_cast<float>(cov));
      }
  }
  composite(mask, bx0, by0, bw, bh, c);
}

double PngCanvas::text_width(std::string_view utf8, FontSize size) const {
  const ImFont* f = font_->get(size);
  double w = 0;
  for (unsigned cp : decode_utf8(utf8))
    if (const ImFontGlyph* g = f->FindGlyph(static_cast<ImWchar>(cp <= 0xFFFF ? cp : 0xFFFD)))
      w += g->AdvanceX;
  return w;
}

double PngCanvas::line_height(FontSize size) const { return font_->get(size)->FontSize; }

void PngCanvas::text(double x, double y, std::string_view utf8, Rgba c, FontSize size, Align align,
                     bool vertical) {
  const ImFont* f = font_->get(size);
  const double w = text_width(utf8, size);
  const double shift = align == Align::Left ? 0.0 : align == Align::Centre ? std::round(w / 2) : w;
  // Pen position along the run; (ox, oy) the origin of the line (its top-left, unrotated).
  const int ox = static_cast<int>(std::lround(vertical ? x : x - shift));
  const int oy = static_cast<int>(std::lround(vertical ? y + shift : y));
  double pen = 0;
  for (unsigned cp : decode_utf8(utf8)) {
    const ImFontGlyph* g = f->FindGlyph(static_cast<ImWchar>(cp <= 0xFFFF ? cp : 0xFFFD));
    if (!g) continue;
    if (g->Visible) {
      const int u0 = static_cast<int>(std::lround(g->U0 * font_->tw)),
                u1 = static_cast<int>(std::lround(g->U1 * font_->tw));
      const int v0 = static_cast<int>(std::lround(g->V0 * font_->th)),
                v1 = static_cast<int>(std::lround(g->V1 * font_->th));
      const int gx = static_cast<int>(std::lround(pen + g->X0)),
                gy = static_cast<int>(std::lround(g->Y0));
      for (int v = v0; v < v1; ++v)
        for (int u = u0; u < u1; ++u) {
          const unsigned char a =
              font_->alpha[static_cast<std::size_t>(v) * static_cast<std::size_t>(font_->tw) +
                           static_cast<std::size_t>(u)];
          if (!a) continue;
          const int lx = gx + (u - u0), ly = gy + (v - v0);  // in the unrotated line
          if (vertical)
            blend(ox + ly, oy - 1 - lx, c, a / 255.0);
          else
            blend(ox + lx, oy + ly, c, a / 255.0);
        }
    }
    pen += g->AdvanceX;
  }
}

void PngCanvas::save_png(const std::filesystem::path& file) const {
  if (!stbi_write_png(file.string().c_str(), w_, h_, 4, px_.data(), w_ * 4))
    throw std::runtime_error("cannot write the PNG file " + file.string());
}

}  // namespace piezo::jobs::report
