#pragma once
// A small CPU raster canvas for headless PNG plots (`piezobench diagnose
// --plot`): anti-aliased lines and polylines with width and dashes, filled
// rectangles and bands with alpha, and text. RGBA, top row first, written with
// stb_image_write. No GL context and no font files: text is Dear ImGui's
// embedded ProggyClean font, rasterised once per canvas by ImFontAtlas on the
// CPU (13 px, its design size, so the glyphs are pixel-exact; 26 px for
// titles). Only ImGui's font atlas is used here — no ImGui context, nothing of
// the GUI (ui/gui) — so jobs/report stays independent of the GUI.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string_view>
#include <vector>

namespace piezo::jobs::report {

struct Rgba {
  std::uint8_t r = 0, g = 0, b = 0, a = 255;
};

struct Point {
  double x = 0, y = 0;  // pixels; a non-finite point breaks a polyline
};

enum class Align { Left, Centre, Right };
enum class FontSize { Normal, Large };  // 13 px and 26 px

class PngCanvas {
 public:
  PngCanvas(int width, int height, Rgba background = {255, 255, 255, 255});
  ~PngCanvas();
  PngCanvas(PngCanvas&&) noexcept;
  PngCanvas& operator=(PngCanvas&&) noexcept;

  int width() const { return w_; }
  int height() const { return h_; }
  const std::vector<std::uint8_t>& rgba() const { return px_; }  // 4 bytes per pixel, rows top-down
  Rgba pixel(int x, int y) const;

  // Drawing is clipped to this rectangle (default: the whole canvas).
  void set_clip(double x0, double y0, double x1, double y1);
  void reset_clip();

  // Pixel (i, j) covers [i, i+1) × [j, j+1); edges at fractional positions are anti-aliased.
  void fill_rect(double x0, double y0, double x1, double y1, Rgba c);
  // The band between two curves sampled at the same increasing x (pixels), linear in between.
  void fill_band(const std::vector<double>& x, const std::vector<double>& y_top,
                 const std::vector<double>& y_bottom, Rgba c);
  void line(Point a, Point b, Rgba c, double width = 1.0);
  // `dash` > 0: dashes and gaps of that many pixels along the curve.
  void polyline(const std::vector<Point>& pts, Rgba c, double width = 1.0, double dash = 0.0);

  // UTF-8 text; `y` is the top of the line. Vertical text reads bottom to top
  // from (x, y) upwards, its top on the left (a y-axis label).
  void text(double x, double y, std::string_view utf8, Rgba c, FontSize size = FontSize::Normal,
            Align align = Align::Left, bool vertical = false);
  double text_width(std::string_view utf8, FontSize size = FontSize::Normal) const;
  double line_height(FontSize size = FontSize::Normal) const;

  // Throws std::runtime_error naming the file when it cannot be written.
  void save_png(const std::filesystem::path& file) const;

 private:
  struct Font;
  void blend(int x, int y, Rgba c, double coverage);
  // Composites a coverage mask over [bx0, bx0 + bw) × [by0, by0 + bh).
  void composite(const std::vector<float>& mask, int bx0, int by0, int bw, int bh, Rgba c);

  int w_ = 0, h_ = 0;
  std::vector<std::uint8_t> px_;
  double cx0_ = 0, cy0_ = 0, cx1_ = 0, cy1_ = 0;  // clip
  std::unique_ptr<Font> font_;
};

}  // namespace piezo::jobs::report
