// The headless SVG plot writer: axis ticks, gaps at unusable points, escaping.
#include <gtest/gtest.h>

#include <cmath>

#include "jobs/report/svg_plot.hpp"

using namespace piezo::jobs::report;

namespace {
std::size_t count(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t i = 0; (i = s.find(what, i)) != std::string::npos; i += what.size()) ++n;
  return n;
}
}  // namespace

TEST(SvgPlot, LogTicksAreDecadesOrFinerOverShortRanges) {
  EXPECT_EQ(log_ticks(100, 120e3), (std::vector<double>{100, 1e3, 1e4, 1e5}));
  EXPECT_EQ(log_ticks(40e3, 110e3), (std::vector<double>{50e3, 100e3}));
  EXPECT_TRUE(log_ticks(-1, 10).empty());
  EXPECT_EQ(tick_label(1e3, Scale::Log), "1k");
  EXPECT_EQ(tick_label(20e3, Scale::Log), "20k");
  EXPECT_EQ(tick_label(100, Scale::Log), "100");
  EXPECT_EQ(tick_label(2e6, Scale::Log), "2M");
}

TEST(SvgPlot, LinearTicksAreRoundNumbersInsideTheRange) {
  EXPECT_EQ(linear_ticks(-95, 95), (std::vector<double>{-50, 0, 50}));
  auto t = linear_ticks(0.31, 0.34);
  ASSERT_GE(t.size(), 3u);
  for (double v : t) {
    EXPECT_GE(v, 0.31 - 1e-12);
    EXPECT_LE(v, 0.34 + 1e-12);
  }
  EXPECT_TRUE(linear_ticks(1, 1).empty());
}

TEST(SvgPlot, UnusablePointsBreakTheLineAndTextIsEscaped) {
  Panel p;
  p.title = "|Z| <measured> & model";
  p.x_scale = p.y_scale = Scale::Log;
  // The NaN and the non-positive value (log axis) each break the line: three runs.
  p.series.push_back({"a&b",
                      {1, 2, 3, 4, 5, 6, 7},
                      {1, 2, std::nan(""), 4, 5, -1, 7},
                      "#000000",
                      1.0,
                      false,
                      false});
  p.series.push_back({"", {1, 2}, {3, 4}, "#ff0000", 1.0, false, true});
  p.markers.push_back({3.0, "#00ff00"});
  Figure f;
  f.title = "T-001";
  f.panels = {p};
  const std::string svg = render_svg(f);
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  // Runs of one point are not drawn: {1,2}, {4,5}, {7} → two polylines.
  EXPECT_EQ(count(svg, "<polyline"), 2u);
  EXPECT_EQ(count(svg, "<circle"), 2u);  // the point series; its empty label has no legend entry
  EXPECT_NE(svg.find("|Z| &lt;measured&gt; &amp; model"), std::string::npos);
  EXPECT_NE(svg.find(">a&amp;b<"), std::string::npos);
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  EXPECT_EQ(svg.find("inf"), std::string::npos);
}
