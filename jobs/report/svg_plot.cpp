#include "jobs/report/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace piezo::jobs::report {

namespace {

constexpr double kLeft = 78, kRight = 24, kTop = 30, kBottom = 44;

bool usable(double v, Scale s) { return std::isfinite(v) && (s == Scale::Linear || v > 0); }

}  // namespace

std::pair<double, double> data_range(const Panel& p, bool x_axis) {
  const Scale s = x_axis ? p.x_scale : p.y_scale;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& ser : p.series) {
    const auto& v = x_axis ? ser.x : ser.y;
    const auto& other = x_axis ? ser.y : ser.x;
    const Scale os = x_axis ? p.y_scale : p.x_scale;
    for (std::size_t i = 0; i < v.size() && i < other.size(); ++i)
      if (usable(v[i], s) && usable(other[i], os)) {
        lo = std::min(lo, v[i]);
        hi = std::max(hi, v[i]);
      }
  }
  if (!x_axis)
    for (const auto& h : p.hlines)
      if (usable(h.y, s)) {
        lo = std::min(lo, h.y);
        hi = std::max(hi, h.y);
      }
  if (!(lo <= hi)) return s == Scale::Log ? std::pair(1.0, 10.0) : std::pair(0.0, 1.0);
  if (s == Scale::Log) {
    if (hi / lo < 1.5) return {lo / 1.5, hi * 1.5};
    return {lo / 1.15, hi * 1.15};
  }
  if (hi - lo <= 1e-12 * std::max(std::abs(lo), std::abs(hi))) {
    const double d = lo == 0 ? 1.0 : 0.1 * std::abs(lo);
    return {lo - d, hi + d};
  }
  const double pad = 0.05 * (hi - lo);
  return {lo - pad, hi + pad};
}

namespace {

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  return b;
}

void text(std::ostringstream& o, double x, double y, const std::string& s, const char* anchor,
          int size = 12, const char* extra = "") {
  o << "<text x=\"" << num(x) << "\" y=\"" << num(y) << "\" font-size=\"" << size
    << "\" text-anchor=\"" << anchor << "\"" << extra << ">" << xml_escape(s) << "</text>\n";
}

void render_panel(std::ostringstream& o, const Panel& p, double x0, double y0, double w, double h,
                  int id) {
  const auto xr = p.x_range.value_or(data_range(p, true));
  const auto yr = p.y_range.value_or(data_range(p, false));
  const Axis ax{xr.first, xr.second, x0 + kLeft, x0 + w - kRight, p.x_scale};
  const Axis ay{yr.first, yr.second, y0 + h - kBottom, y0 + kTop, p.y_scale};
  const double pw = ax.px1 - ax.px0, ph = ay.px0 - ay.px1;
  o << "<clipPath id=\"clip" << id << "\"><rect x=\"" << num(ax.px0) << "\" y=\"" << num(ay.px1)
    << "\" width=\"" << num(pw) << "\" height=\"" << num(ph) << "\"/></clipPath>\n";
  o << "<rect x=\"" << num(ax.px0) << "\" y=\"" << num(ay.px1) << "\" width=\"" << num(pw)
    << "\" height=\"" << num(ph) << "\" fill=\"#ffffff\" stroke=\"#333333\"/>\n";
  // Grid and tick labels.
  const auto xt = p.x_scale == Scale::Log ? log_ticks(ax.lo, ax.hi) : linear_ticks(ax.lo, ax.hi);
  const auto yt = p.y_scale == Scale::Log ? log_ticks(ay.lo, ay.hi) : linear_ticks(ay.lo, ay.hi);
  for (double t : xt) {
    const double x = ax.to_px(t);
    o << "<line x1=\"" << num(x) << "\" y1=\"" << num(ay.px1) << "\" x2=\"" << num(x) << "\" y2=\""
      << num(ay.px0) << "\" stroke=\"#e4e4e4\"/>\n";
    text(o, x, ay.px0 + 16, tick_label(t, p.x_scale), "middle", 11);
  }
  for (double t : yt) {
    const double y = ay.to_px(t);
    o << "<line x1=\"" << num(ax.px0) << "\" y1=\"" << num(y) << "\" x2=\"" << num(ax.px1)
      << "\" y2=\"" << num(y) << "\" stroke=\"#e4e4e4\"/>\n";
    text(o, ax.px0 - 6, y + 4, tick_label(t, p.y_scale), "end", 11);
  }
  text(o, x0 + w / 2, y0 + 18, p.title, "middle", 14, " font-weight=\"bold\"");
  text(o, (ax.px0 + ax.px1) / 2, ay.px0 + 34, p.x_label, "middle");
  {
    const double cx = x0 + 16, cy = (ay.px0 + ay.px1) / 2;
    o << "<text x=\"" << num(cx) << "\" y=\"" << num(cy)
      << "\" font-size=\"12\" text-anchor=\"middle\" transform=\"rotate(-90 " << num(cx) << " "
      << num(cy) << ")\">" << xml_escape(p.y_label) << "</text>\n";
  }
  o << "<g clip-path=\"url(#clip" << id << ")\">\n";
  for (const auto& m : p.markers) {
    if (!usable(m.x, p.x_scale)) continue;
    const double x = ax.to_px(m.x);
    o << "<line x1=\"" << num(x) << "\" y1=\"" << num(ay.px1) << "\" x2=\"" << num(x) << "\" y2=\""
      << num(ay.px0) << "\" stroke=\"" << m.colour << "\" stroke-dasharray=\"3 3\"/>\n";
  }
  for (const auto& hl : p.hlines) {
    if (!usable(hl.y, p.y_scale)) continue;
    const double y = ay.to_px(hl.y);
    o << "<line x1=\"" << num(ax.px0) << "\" y1=\"" << num(y) << "\" x2=\"" << num(ax.px1)
      << "\" y2=\"" << num(y) << "\" stroke=\"" << hl.colour << "\""
      << (hl.dashed ? " stroke-dasharray=\"6 4\"" : "") << "/>\n";
    if (!hl.label.empty())  // above the line, or below it when the line runs along the top
      text(o, ax.px1 - 4, y - 4 < ay.px1 + 10 ? y + 12 : y - 4, hl.label, "end", 10,
           " fill=\"#555555\"");
  }
  for (const auto& s : p.series) {
    const std::size_t n = std::min(s.x.size(), s.y.size());
    if (s.points) {
      for (std::size_t i = 0; i < n; ++i)
        if (usable(s.x[i], p.x_scale) && usable(s.y[i], p.y_scale))
          o << "<circle cx=\"" << num(ax.to_px(s.x[i])) << "\" cy=\"" << num(ay.to_px(s.y[i]))
            << "\" r=\"" << num(std::max(2.0, s.width)) << "\" fill=\"" << s.colour << "\"/>\n";
      continue;
    }
    std::string pts;
    auto flush = [&] {
      if (pts.find(' ') != std::string::npos)  // at least two points
        o << "<polyline fill=\"none\" stroke=\"" << s.colour << "\" stroke-width=\"" << num(s.width)
          << "\"" << (s.dashed ? " stroke-dasharray=\"7 4\"" : "")
          << " stroke-linejoin=\"round\" points=\"" << pts << "\"/>\n";
      pts.clear();
    };
    for (std::size_t i = 0; i < n; ++i) {
      if (!usable(s.x[i], p.x_scale) || !usable(s.y[i], p.y_scale)) {
        flush();
        continue;
      }
      if (!pts.empty()) pts += ' ';
      pts += num(ax.to_px(s.x[i])) + "," + num(ay.to_px(s.y[i]));
    }
    flush();
  }
  o << "</g>\n";
  // Legend, top right inside the plot area, on a translucent card.
  std::size_t entries = 0;
  for (const auto& s : p.series) entries += !s.label.empty();
  if (entries)
    o << "<rect x=\"" << num(ax.px1 - 196) << "\" y=\"" << num(ay.px1 + 3)
      << "\" width=\"192\" height=\"" << num(15.0 * static_cast<double>(entries) + 6)
      << "\" fill=\"#ffffff\" fill-opacity=\"0.85\" stroke=\"#cccccc\"/>\n";
  double ly = ay.px1 + 18;
  for (const auto& s : p.series) {
    if (s.label.empty()) continue;
    const double lx = ax.px1 - 190;
    if (s.points)
      o << "<circle cx=\"" << num(lx + 11) << "\" cy=\"" << num(ly - 4) << "\" r=\"3\" fill=\""
        << s.colour << "\"/>\n";
    else
      o << "<line x1=\"" << num(lx) << "\" y1=\"" << num(ly - 4) << "\" x2=\"" << num(lx + 22)
        << "\" y2=\"" << num(ly - 4) << "\" stroke=\"" << s.colour << "\" stroke-width=\""
        << num(std::min(s.width, 4.0)) << "\"" << (s.dashed ? " stroke-dasharray=\"7 4\"" : "")
        << "/>\n";
    text(o, lx + 28, ly, s.label, "start", 11);
    ly += 15;
  }
}

}  // namespace

std::vector<double> linear_ticks(double lo, double hi, int target) {
  std::vector<double> out;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi) || target < 2) return out;
  const double raw = (hi - lo) / (target - 1);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  for (double t = std::ceil(lo / step) * step; t <= hi + 1e-9 * step; t += step)
    out.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  return out;
}

std::vector<double> log_ticks(double lo, double hi) {
  std::vector<double> out;
  if (!(hi > lo) || !(lo > 0) || !std::isfinite(hi)) return out;
  const bool fine = std::log10(hi / lo) < 2.0;
  for (int e = static_cast<int>(std::floor(std::log10(lo)));
       e <= static_cast<int>(std::ceil(std::log10(hi))); ++e)
    for (double m : {1.0, 2.0, 5.0}) {
      if (m != 1.0 && !fine) continue;
      const double t = m * std::pow(10.0, e);
      if (t >= lo * (1 - 1e-12) && t <= hi * (1 + 1e-12)) out.push_back(t);
    }
  return out;
}

std::string tick_label(double v, Scale s) {
  char b[32];
  if (s == Scale::Log && v > 0) {
    // SI prefixes for the usual ranges (Hz, ohm): 100, 1k, 20k, 1M.
    static constexpr std::pair<double, const char*> kPrefix[] = {
        {1e9, "G"},  {1e6, "M"},  {1e3, "k"},  {1.0, ""},
        {1e-3, "m"}, {1e-6, "u"}, {1e-9, "n"}, {1e-12, "p"}};
    for (const auto& [f, p] : kPrefix)
      if (v >= f * (1 - 1e-9)) {
        std::snprintf(b, sizeof b, "%g%s", v / f, p);
        return b;
      }
  }
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

std::string xml_escape(const std::string& s) {
  std::string o;
  for (char c : s) switch (c) {
      case '&':
        o += "&amp;";
        break;
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '"':
        o += "&quot;";
        break;
      default:
        o += c;
    }
  return o;
}

std::string render_svg(const Figure& fig) {
  const double title_h = fig.title.empty() ? 0 : 28;
  const double h = title_h + fig.panel_height * static_cast<double>(fig.panels.size());
  std::ostringstream o;
  o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << fig.width << "\" height=\"" << num(h)
    << "\" viewBox=\"0 0 " << fig.width << " " << num(h) << "\" font-family=\"sans-serif\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"#fafafa\"/>\n";
  if (!fig.title.empty())
    text(o, fig.width / 2.0, 20, fig.title, "middle", 15, " font-weight=\"bold\"");
  for (std::size_t k = 0; k < fig.panels.size(); ++k)
    render_panel(o, fig.panels[k], 0, title_h + fig.panel_height * static_cast<double>(k),
                 fig.width, fig.panel_height, static_cast<int>(k));
  o << "</svg>\n";
  return o.str();
}

void write_svg(const Figure& fig, const std::filesystem::path& file) {
  std::ofstream f(file);
  if (!f) throw std::runtime_error("report: cannot write " + file.string());
  f << render_svg(fig);
  if (!f.flush()) throw std::runtime_error("report: cannot write " + file.string());
}

}  // namespace piezo::jobs::report
