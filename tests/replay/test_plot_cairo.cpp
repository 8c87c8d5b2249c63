// The plot description's axes (jobs/report/plot_axes) and its Cairo renderer
// (jobs/report/plot_cairo): ticks and labels, gaps at unusable points, the
// SVG's structure and coordinates, and the PNG's pixels.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <regex>

#include "jobs/report/plot_axes.hpp"
#include "jobs/report/plot_cairo.hpp"

using namespace piezo::jobs::report;

namespace {
std::size_t count(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t i = 0; (i = s.find(what, i)) != std::string::npos; i += what.size()) ++n;
  return n;
}

// The d="" of every <path> whose style holds `style` (Cairo writes one path per stroke or fill).
std::vector<std::string> paths_with(const std::string& svg, const std::string& style) {
  std::vector<std::string> out;
  const std::regex path("<path style=\"([^\"]*)\" d=\"([^\"]*)\"");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), path); it != std::sregex_iterator(); ++it)
    if ((*it)[1].str().find(style) != std::string::npos) out.push_back((*it)[2].str());
  return out;
}
}  // namespace

TEST(PlotAxes, LogTicksAreDecadesOrFinerOverShortRanges) {
  EXPECT_EQ(log_ticks(100, 120e3, false), (std::vector<double>{100, 1e3, 1e4, 1e5}));
  EXPECT_EQ(log_ticks(40e3, 110e3, true), (std::vector<double>{50e3, 100e3}));
  EXPECT_TRUE(log_ticks(-1, 10, true).empty());
  EXPECT_EQ(log_minor_ticks(80, 300), (std::vector<double>{80, 90, 100, 200, 300}));
  EXPECT_EQ(tick_label(1e3, Scale::Log), "1k");
  EXPECT_EQ(tick_label(20e3, Scale::Log), "20k");
  EXPECT_EQ(tick_label(100, Scale::Log), "100");
  EXPECT_EQ(tick_label(2e6, Scale::Log), "2M");
  EXPECT_EQ(tick_label(20e3, Scale::Log, "Hz"), "20 kHz");
  EXPECT_EQ(tick_label(-0.5, Scale::Linear, "dB"), "-0.5 dB");
}

TEST(PlotAxes, LinearTicksAreRoundNumbersInsideTheRange) {
  EXPECT_EQ(linear_ticks(-95, 95), (std::vector<double>{-50, 0, 50}));
  auto t = linear_ticks(0.31, 0.34);
  ASSERT_GE(t.size(), 3u);
  for (double v : t) {
    EXPECT_GE(v, 0.31 - 1e-12);
    EXPECT_LE(v, 0.34 + 1e-12);
  }
  EXPECT_TRUE(linear_ticks(1, 1).empty());
}

// The labelled ticks follow the room: 1-2-5 on a long axis, decades on a
// short one, every other decade when even those crowd; the rest is grid.
TEST(PlotAxes, TicksFitTheAxisLength) {
  const auto wide = axis_ticks(100, 120e3, Scale::Log, 800, 30);
  EXPECT_EQ(wide.major.size(), 10u);  // 100 200 500 1k ... 100k
  EXPECT_EQ(wide.major.front(), 100);
  EXPECT_FALSE(wide.minor.empty());   // 300, 400, ...
  const auto narrow = axis_ticks(100, 120e3, Scale::Log, 300, 30);
  EXPECT_EQ(narrow.major, (std::vector<double>{100, 1e3, 1e4, 1e5}));
  const auto crowded = axis_ticks(1e-3, 1e6, Scale::Log, 150, 30);
  EXPECT_LE(crowded.major.size(), 5u);
  EXPECT_GE(crowded.major.size(), 2u);
  for (double v : crowded.major) EXPECT_NEAR(std::log10(v), std::round(std::log10(v)), 1e-12);
  EXPECT_EQ(axis_ticks(0, 10, Scale::Linear, 70, 13).major, (std::vector<double>{0, 5, 10}));
  EXPECT_EQ(axis_ticks(0, 10, Scale::Linear, 300, 13).major.size(), 6u);  // 0, 2, ... 10
}

// One view the GUI opens on: framed x, the y range from the samples inside it, padded.
TEST(PlotAxes, FitRangeFramesTheData) {
  Panel p;
  p.series.push_back({"", {1, 2, 3, 4, 5}, {0, 10, 20, 30, 1000}});
  p.fit_x0 = 2;
  p.fit_x1 = 4;
  const auto r = fit_range(p);
  EXPECT_DOUBLE_EQ(r.x0, 2);
  EXPECT_DOUBLE_EQ(r.x1, 4);
  EXPECT_DOUBLE_EQ(r.y0, 10 - 0.05 * 20);
  EXPECT_DOUBLE_EQ(r.y1, 30 + 0.05 * 20);
  const auto all = fit_range(p, true);
  EXPECT_DOUBLE_EQ(all.x0, 1);
  EXPECT_DOUBLE_EQ(all.y1, 1000 + 0.05 * 1000);
}

TEST(PlotCairo, SvgPathsBreakAtUnusablePointsAndSitWhereTheAxesSay) {
  Panel p;
  p.x_range = std::pair(0.0, 10.0);
  p.y_range = std::pair(0.0, 10.0);
  // The NaN and the infinity break the line: {1,2}, {4,5}, {7} (a run of one point draws nothing).
  p.series.push_back({"a&b", {1, 2, 3, 4, 5, 6, 7}, {1, 2, std::nan(""), 4, 5, INFINITY, 7}, "#0000ff", 1.0});
  p.series.push_back({"", {1, 2}, {3, 4}, "#ff0000", 1.0, false, true});
  p.markers.push_back({3.0, "#00ff00"});
  Figure f;
  f.title = "T-001 <measured> & model";
  f.panels = {p};
  const std::string svg = render_svg(f);
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  const auto l = layout_figure(f);
  EXPECT_EQ(l.width, 900);
  EXPECT_EQ(l.height, 30 + 4 + 300);  // the title line, then one panel
  EXPECT_NE(svg.find("viewBox=\"0 0 900 334\""), std::string::npos) << svg.substr(0, 300);
  // The blue curve: one stroked path of two drawn runs, each one segment long; then
  // its sample in the legend (one segment).
  const auto blue = paths_with(svg, "stroke:rgb(0%,0%,100%)");
  ASSERT_EQ(blue.size(), 2u) << svg;
  EXPECT_EQ(count(blue[1], "M "), 1u) << blue[1];
  // (The lone {7} is a move without a line: with butt caps it draws nothing.)
  EXPECT_EQ(count(blue[0], "M "), 3u) << blue[0];
  EXPECT_EQ(count(blue[0], "L "), 2u) << blue[0];
  // The second run starts at the sample (4, 4), where the panel's plot area
  // puts it (Cairo keeps 1/256 pixel).
  const PixelRect& r = l.plots[0];
  double x = 0, y = 0;
  ASSERT_EQ(std::sscanf(blue[0].c_str() + blue[0].find("M ", 1), "M %lf %lf", &x, &y), 2) << blue[0];
  EXPECT_NEAR(x, r.x0 + 0.4 * (r.x1 - r.x0), 0.01) << blue[0];
  EXPECT_NEAR(y, r.y1 - 0.4 * (r.y1 - r.y0), 0.01) << blue[0];
  // The point series: one fill of two circles; the marker: a dashed green stroke.
  const auto red = paths_with(svg, "fill:rgb(100%,0%,0%)");
  ASSERT_EQ(red.size(), 1u);
  EXPECT_EQ(count(red[0], "M "), 2u);
  const auto green = paths_with(svg, "stroke:rgb(0%,100%,0%)");
  ASSERT_EQ(green.size(), 1u);
  EXPECT_NE(svg.find("stroke-dasharray:3,3"), std::string::npos);
  // Text is drawn as glyphs: the title's and the legend's ("a&b"; the point series has no label).
  EXPECT_GT(count(svg, "<use xlink:href=\"#glyph"), std::string("T-001<measured>&model").size());
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  EXPECT_EQ(svg.find("inf"), std::string::npos);
}

TEST(PlotCairo, RasterShowsTheCurvesInTheirColours) {
  Panel p;
  p.x_range = std::pair(0.0, 10.0);
  p.y_range = std::pair(0.0, 10.0);
  p.series.push_back({"", {0, 10}, {5, 5}, "#0000ff", 3.0});
  p.bands.push_back({6, 8, "#ffee00"});
  Figure f;
  f.panels = {p};
  const Raster img = render_raster(f);
  const auto l = layout_figure(f);
  ASSERT_EQ(img.width, l.width);
  ASSERT_EQ(img.height, l.height);
  const PixelRect& r = l.plots[0];
  const int ymid = static_cast<int>(std::lround((r.y0 + r.y1) / 2 - 0.5));
  const int x3 = static_cast<int>(r.x0 + 0.3 * (r.x1 - r.x0));  // off the grid lines (0, 2, 4, ...)
  EXPECT_EQ(img.pixel(x3, ymid), (Colour{0, 0, 255}));                 // the curve
  EXPECT_EQ(img.pixel(x3, ymid + 10), (Colour{255, 255, 255}));        // the plot area
  const int x7 = static_cast<int>(r.x0 + 0.7 * (r.x1 - r.x0));
  EXPECT_EQ(img.pixel(x7, static_cast<int>(r.y0) + 40), (Colour{255, 238, 0}));  // the band
  EXPECT_EQ(img.pixel(2, 2), (Colour{250, 250, 250}));                 // the figure's background
  EXPECT_THROW(img.pixel(img.width, 0), std::out_of_range);
}

TEST(PlotCairo, ColoursParseLikeCss) {
  EXPECT_EQ(Colour("#d62728"), (Colour{0xd6, 0x27, 0x28}));
  EXPECT_EQ(Colour("#d6272880").a, 0x80);
  EXPECT_EQ(Colour("red"), (Colour{136, 136, 136}));
  EXPECT_EQ(Colour("#zz0000"), (Colour{136, 136, 136}));
}
