// jobs/report/lot_summary and lot_report: counts, distribution, histogram,
// robust outliers and the capability indices against hand computations; the
// lot report's files, and its histogram figure as SVG and PNG (the limits
// drawn where they belong).
#include <gtest/gtest.h>

#include <regex>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "jobs/report/plot_cairo.hpp"
#include "jobs/report/lot_report.hpp"
#include "jobs/report/lot_summary.hpp"

using namespace piezo::jobs::report;
namespace fs = std::filesystem;

namespace {

LotRecord rec(const std::string& path, std::optional<double> x,
              const std::string& verdict = "none") {
  nlohmann::json r = {{"diagnosis", {{"verdict_effect", verdict}}}};
  if (x) r["x"] = *x;
  return {path, "k" + path, {{"status", "ok"}, {"result", r}}};
}

Limits limits(const std::string& x_range) {
  return parse_limits(
      "[[limit]]\nquantity = \"x\"\nunit = \"Hz\"\n" + x_range +
          "\n[[limit]]\nquantity = \"diagnosis.verdict_effect\"\nallowed = [\"none\"]\n",
      "lot.toml");
}

}  // namespace

TEST(LotSummary, CapabilityMatchesAHandComputation) {
  // mean 10, sample sd 2 (values 8, 10, 12 → ss = 8, /2 = 4).
  const Limits two = limits("min = 4.0\nmax = 19.0");
  const auto c = capability(two.limits[0], 10.0, 2.0, 3);
  ASSERT_TRUE(c.cpk && c.cp && c.cpu && c.cpl);
  EXPECT_DOUBLE_EQ(*c.cpu, (19.0 - 10.0) / 6.0);  // 1.5
  EXPECT_DOUBLE_EQ(*c.cpl, (10.0 - 4.0) / 6.0);   // 1.0
  EXPECT_DOUBLE_EQ(*c.cpk, 1.0);
  EXPECT_DOUBLE_EQ(*c.cp, 15.0 / 12.0);
  EXPECT_FALSE(c.one_sided);

  const Limits upper = limits("max = 16.0");
  const auto u = capability(upper.limits[0], 10.0, 2.0, 3);
  EXPECT_TRUE(u.one_sided);
  EXPECT_FALSE(u.cp);
  EXPECT_FALSE(u.cpl);
  EXPECT_DOUBLE_EQ(*u.cpu, 1.0);
  EXPECT_DOUBLE_EQ(*u.cpk, 1.0);

  const Limits lower = limits("min = 7.0");
  EXPECT_DOUBLE_EQ(*capability(lower.limits[0], 10.0, 2.0, 3).cpl, 0.5);
  EXPECT_FALSE(capability(two.limits[0], 10.0, 0.0, 3).cpk);  // σ = 0: no index
  EXPECT_FALSE(capability(two.limits[0], 10.0, 2.0, 1).cpk);  // one value: no σ
}

TEST(LotSummary, HistogramBinsIncludeTheTopEdge) {
  const auto h = histogram({0.0, 0.5, 1.0, 2.5, 4.0, 7.0}, 0.0, 4.0, 4);
  // [0,1): 0, 0.5; [1,2): 1; [2,3): 2.5; [3,4]: 4 (the top edge); 7 is outside: not counted.
  EXPECT_EQ(h.counts, (std::vector<std::size_t>{2, 1, 1, 1}));
  EXPECT_DOUBLE_EQ(h.width(), 1.0);
  EXPECT_EQ(default_bins(200), 15);
  EXPECT_EQ(default_bins(3), 5);
  EXPECT_EQ(default_bins(10000), 30);
}

TEST(LotSummary, CountsStatisticsOutliersAndCategories) {
  const Limits L = limits("min = 9.0\nmax = 13.0");
  std::vector<LotRecord> rs = {
      rec("a", 10.0),
      rec("b", 11.0),
      rec("c", 12.0),
      rec("d", 11.0),
      rec("e", 11.0),
      rec("f", 30.0, "mass_loading"),  // above max, an outlier, a verdict not allowed
      rec("g", std::nullopt),          // not measured
      {"h", "kh", {{"status", "failed"}, {"error", {{"message", "truncated"}}}}}};
  const auto s = summarize_lot(L, rs);
  EXPECT_EQ(s.captures.size(), 8u);
  EXPECT_EQ(s.pass, 5u);
  EXPECT_EQ(s.fail, 2u);
  EXPECT_EQ(s.error, 1u);
  ASSERT_EQ(s.quantities.size(), 2u);
  const auto& q = s.quantities[0];
  EXPECT_EQ(q.n, 6u);
  EXPECT_EQ(q.not_measured, 1u);
  EXPECT_EQ(q.below, 0u);
  EXPECT_EQ(q.above, 1u);
  const double mean = (10 + 11 + 12 + 11 + 11 + 30) / 6.0;
  double ss = 0;
  for (double x : {10.0, 11.0, 12.0, 11.0, 11.0, 30.0}) ss += (x - mean) * (x - mean);
  EXPECT_DOUBLE_EQ(q.mean, mean);
  EXPECT_NEAR(q.sd, std::sqrt(ss / 5.0), 1e-12);
  EXPECT_EQ(q.min, 10.0);
  EXPECT_EQ(q.max, 30.0);
  EXPECT_EQ(q.robust.median, 11.0);
  ASSERT_EQ(q.outliers.size(), 1u);
  EXPECT_EQ(s.captures[q.outliers[0]].path, "f");
  EXPECT_NEAR(*q.capability.cpk, (13.0 - mean) / (3 * q.sd), 1e-12);
  std::size_t binned = 0;
  for (auto c : q.histogram.counts) binned += c;
  EXPECT_EQ(binned, 6u);
  EXPECT_LE(q.histogram.lo, 9.0);  // the histogram spans the limits too
  const auto& v = s.quantities[1];
  EXPECT_EQ(v.n, 7u);
  EXPECT_EQ(v.not_allowed, 1u);
  EXPECT_EQ(v.categories.at("none"), 6u);
  EXPECT_EQ(v.categories.at("mass_loading"), 1u);

  const auto j = lot_json(L, s);
  EXPECT_EQ(j["pass"], 5);
  EXPECT_EQ(j["fail"], 2);
  EXPECT_EQ(j["error"], 1);
  EXPECT_EQ(j["quantities"][0]["n"], 6);
  EXPECT_EQ(j["quantities"][0]["outliers"][0]["path"], "f");
  EXPECT_EQ(j["quantities"][0]["cpk"], *q.capability.cpk);
  EXPECT_EQ(j["quantities"][1]["values"]["none"], 6);
  EXPECT_EQ(j["failures"].size(), 3u);
}

TEST(LotReport, WritesMarkdownJsonAndTheHistogramsAsSvgAndPng) {
  const Limits L = limits("min = 9.0\nmax = 13.0");
  std::vector<LotRecord> rs;
  for (int k = 0; k < 40; ++k) {
    char name[16];
    std::snprintf(name, sizeof name, "t%03d",
                  100 + k);  // (GCC 12's -Wrestrict misfires on "t" + to_string)
    rs.push_back(rec(name, 11.0 + 0.1 * ((k * 7) % 13 - 6)));
  }
  rs.push_back(rec("t999", 14.0));
  const auto s = summarize_lot(L, rs);
  const fs::path dir = fs::temp_directory_path() / "lot-report";
  fs::remove_all(dir);
  write_lot_report(L, s, "results.h5", dir);
  for (const char* f : {"lot.md", "lot.json", "lot_histograms.svg", "lot_histograms.png"})
    EXPECT_TRUE(fs::is_regular_file(dir / f)) << f;
  std::ifstream md(dir / "lot.md");
  std::stringstream text;
  text << md.rdbuf();
  EXPECT_NE(text.str().find("40 pass, 1 fail"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("| t999 | fail | x = 14 Hz > max 13 Hz |"), std::string::npos)
      << text.str();

  const Figure fig = lot_figure(L, s);
  ASSERT_EQ(fig.panels.size(), 1u);  // the allowed list has no histogram
  const auto& p = fig.panels[0];
  bool lo = false, hi = false;
  for (const auto& ser : p.series) {
    lo |= ser.label == "limits" && ser.x == std::vector<double>{9.0, 9.0};
    hi |= ser.colour == "#d62728" && ser.dashed && ser.x == std::vector<double>{13.0, 13.0};
  }
  EXPECT_TRUE(lo && hi);
  // The SVG: the limits' dashed red strokes (Cairo writes colours in per cent: #d62728).
  const std::string svg = render_svg(fig);
  std::size_t dashed_red = 0;
  const std::regex style("<path style=\"([^\"]*)\"");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), style); it != std::sregex_iterator(); ++it)
    dashed_red += (*it)[1].str().find("stroke:rgb(83.921569%,15.294118%,15.686275%)") != std::string::npos &&
                  (*it)[1].str().find("stroke-dasharray") != std::string::npos;
  EXPECT_GE(dashed_red, 2u) << "the two limit lines (and the legend's sample)";

  // The PNG: the limit lines' red is found in the plot near x = 9 and 13.
  const Raster c = render_raster(fig);
  EXPECT_EQ(c.width, fig.width);
  const auto [x0, x1] = *p.x_range;
  const PixelRect plot = layout_figure(fig).plots[0];
  auto red_near = [&](double v) {
    const double px = plot.x0 + (v - x0) / (x1 - x0) * (plot.x1 - plot.x0);
    for (int x = static_cast<int>(px) - 2; x <= static_cast<int>(px) + 2; ++x)
      for (int y = static_cast<int>(plot.y0) + 30; y < static_cast<int>(plot.y1); ++y) {
        const auto q = c.pixel(x, y);
        if (q.r > 180 && q.g < 90 && q.b < 90) return true;
      }
    return false;
  };
  EXPECT_TRUE(red_near(9.0));
  EXPECT_TRUE(red_near(13.0));
  EXPECT_FALSE(red_near(11.0));
}
