#include "jobs/report/lot_report.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "jobs/json/json_text.hpp"
#include "jobs/report/plot_cairo.hpp"
#include "jobs/report/markdown.hpp"

namespace piezo::jobs::report {

namespace fs = std::filesystem;

namespace {

std::string opt_num(const std::optional<double>& v, const char* f = "%.3g") {
  return v ? fmt(f, *v) : "-";
}

std::string range_text(const Limit& l) {
  if (!l.numeric()) {
    std::string s;
    for (const auto& a : l.allowed)
      s += (s.empty() ? "" : ", ") + (a.is_string() ? a.get<std::string>() : a.dump());
    return "one of " + s;
  }
  const std::string u = l.unit.empty() ? "" : " " + l.unit;
  if (l.min && l.max) return fmt("%.6g", *l.min) + " … " + fmt("%.6g", *l.max) + u;
  if (l.min) return "≥ " + fmt("%.6g", *l.min) + u;
  return "≤ " + fmt("%.6g", *l.max) + u;
}

}  // namespace

std::string lot_markdown(const Limits& L, const LotSummary& s, const std::string& results_file) {
  std::ostringstream o;
  o << "# Lot report" << (s.name.empty() ? "" : ": " + s.name) << "\n\n"
    << "- results: `" << results_file << "`\n"
    << "- limits: `" << s.limits_file << "`\n"
    << "- captures: " << s.captures.size() << " — **" << s.pass << " pass, " << s.fail
    << " fail**, " << s.error << " error (replay failed, not judged)\n\n"
    << "A capture passes when every limit passes (bounds included); a quantity that was not "
       "measured "
       "fails it. Cp = (USL − LSL)/6σ, Cpk = min(USL − μ, μ − LSL)/3σ (μ mean, σ sample sd); "
       "one-sided "
       "limits give Cpu or Cpl only. Outliers: modified z-score 0.6745·|x − median|/MAD above "
    << fmt("%.1f", L.outlier_z) << ".\n\n"
    << "## Quantities\n\n"
    << "| quantity | limit | n | fail low | fail high | not measured | mean | sd | min | max | Cp "
       "| Cpk | "
       "outliers |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- "
       "|\n";
  for (const auto& q : s.quantities) {
    const Limit& l = L.limits[q.limit];
    o << "| " << cell(l.label) << (l.label != l.quantity ? " (`" + cell(l.quantity) + "`)" : "")
      << " | " << cell(range_text(l)) << " | " << q.n << " | ";
    if (l.numeric()) {
      const char* cap = q.capability.one_sided ? (l.max ? " (Cpu)" : " (Cpl)") : "";
      o << q.below << " | " << q.above << " | " << q.not_measured << " | " << fmt("%.6g", q.mean)
        << " | " << fmt("%.3g", q.sd) << " | " << fmt("%.6g", q.min) << " | " << fmt("%.6g", q.max)
        << " | " << opt_num(q.capability.cp) << " | " << opt_num(q.capability.cpk) << cap << " | "
        << q.outliers.size() << " |\n";
    } else {
      std::string vals;
      for (const auto& [v, c] : q.categories)
        vals += (vals.empty() ? "" : ", ") + v + " " + std::to_string(c);
      o << q.not_allowed << " not allowed | - | " << q.not_measured << " | " << cell(vals)
        << " | - | - | - | - | - | - |\n";
    }
  }
  o << "\n![histograms](lot_histograms.png)\n\n(also as [SVG](lot_histograms.svg))\n";
  bool any = false;
  for (const auto& q : s.quantities)
    for (std::size_t i : q.outliers) {
      if (!any)
        o << "\n## Outliers\n\n| capture | quantity | value | median | modified z |\n| --- | --- | "
             "--- | --- | --- |\n";
      any = true;
      double x = 0;
      for (const auto& [k, v] : q.values)
        if (k == i) x = v;
      o << "| " << cell(s.captures[i].path) << " | " << cell(L.limits[q.limit].label) << " | "
        << fmt("%.6g", x) << " | " << fmt("%.6g", q.robust.median) << " | "
        << fmt("%+.1f", modified_z(x, q.robust)) << " |\n";
    }
  if (!any) o << "\nNo outliers.\n";
  o << "\n## Failed and unjudged captures\n\n";
  if (s.fail + s.error == 0)
    o << "None.\n";
  else {
    o << "| capture | status | reasons |\n| --- | --- | --- |\n";
    for (const auto& c : s.captures)
      if (c.verdict.status != "pass") {
        std::string r;
        for (const auto& x : c.verdict.reasons) r += (r.empty() ? "" : "; ") + x;
        o << "| " << cell(c.path) << " | " << c.verdict.status << " | " << cell(r) << " |\n";
      }
  }
  return o.str();
}

Figure lot_figure(const Limits& L, const LotSummary& s) {
  Figure fig;
  fig.title = "Lot " + (s.name.empty() ? std::string() : s.name + " ") + "- " +
              std::to_string(s.pass) + " pass, " + std::to_string(s.fail) + " fail, " +
              std::to_string(s.error) + " error of " + std::to_string(s.captures.size());
  fig.width = 900;
  fig.panel_height = 240;
  for (const auto& q : s.quantities) {
    const Limit& l = L.limits[q.limit];
    if (!l.numeric() || q.histogram.counts.empty()) continue;
    Panel p;
    p.title = l.label + ": n " + std::to_string(q.n) + ", mean " + fmt("%.5g", q.mean) + ", sd " +
              fmt("%.3g", q.sd) +
              (q.capability.cpk ? ", Cpk " + fmt("%.2f", *q.capability.cpk) : "");
    p.x_label = l.unit.empty() ? l.quantity : l.quantity + " [" + l.unit + "]";
    p.y_label = "captures";
    const auto& h = q.histogram;
    Series bars{"", {}, {}, "#1f77b4", 2.0, false, false};
    double top = 0;
    for (std::size_t k = 0; k < h.counts.size(); ++k) {
      const double a = h.lo + h.width() * static_cast<double>(k), b = a + h.width(),
                   c = static_cast<double>(h.counts[k]);
      bars.x.insert(bars.x.end(), {a, a, b, b});
      bars.y.insert(bars.y.end(), {0.0, c, c, 0.0});
      top = std::max(top, c);
    }
    p.series.push_back(std::move(bars));
    auto vline = [&](double x, const std::string& label, const char* colour, bool dashed) {
      p.series.push_back({label, {x, x}, {0.0, top * 1.6 + 1.0}, colour, 1.5, dashed, false});
    };
    // One legend entry for the limits (their values are in the report's table).
    if (l.min) vline(*l.min, "limits", "#d62728", true);
    if (l.max) vline(*l.max, l.min ? "" : "limits", "#d62728", true);
    vline(q.mean, "mean", "#555555", false);
    Series out{"outliers (robust)", {}, {}, "#d62728", 3.0, false, true};
    for (std::size_t i : q.outliers)
      for (const auto& [k, v] : q.values)
        if (k == i) {
          out.x.push_back(v);
          out.y.push_back(0.0);
        }
    if (!out.x.empty()) p.series.push_back(std::move(out));
    // The limits stay in view where the whole lot lies beyond one of them.
    double x0 = h.lo, x1 = h.hi;
    for (const auto& lim : {l.min, l.max})
      if (lim) x0 = std::min(x0, *lim), x1 = std::max(x1, *lim);
    const double pad = x0 < h.lo || x1 > h.hi ? 0.03 * (x1 - x0) : 0.0;
    p.x_range = std::pair(x0 < h.lo ? x0 - pad : x0, x1 > h.hi ? x1 + pad : x1);
    p.y_range = std::pair(0.0, top * 1.6 + 1.0);  // headroom: the legend sits top right
    fig.panels.push_back(std::move(p));
  }
  return fig;
}

void write_lot_report(const Limits& L, const LotSummary& s, const std::string& results_file,
                      const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error("report: cannot create " + dir.string() + ": " + ec.message());
  const Figure fig = lot_figure(L, s);
  write_svg(fig, dir / "lot_histograms.svg");
  write_png(fig, dir / "lot_histograms.png");
  auto text = [](const fs::path& f, const std::string& body) {
    std::ofstream o(f);
    if (!o || !(o << body) || !o.flush())
      throw std::runtime_error("report: cannot write " + f.string());
  };
  text(dir / "lot.md", lot_markdown(L, s, results_file));
  text(dir / "lot.json", jobs::json_text(lot_json(L, s)) + "\n");
}

}  // namespace piezo::jobs::report
