// Axes, ranges and ticks of the plot description (see plot_axes.hpp).
#include "jobs/report/plot_axes.hpp"

#include <algorithm>
#include <cstdio>
#include <limits>

namespace piezo::jobs::report {

std::pair<double, double> data_range(const Panel& p, bool x_axis) {
  const Scale s = x_axis ? p.x_scale : p.y_scale;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  auto take = [&](double v) {
    if (!usable(v, s)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  };
  for (const auto& ser : p.series) {
    const auto& v = x_axis ? ser.x : ser.y;
    const auto& other = x_axis ? ser.y : ser.x;
    const Scale os = x_axis ? p.y_scale : p.x_scale;
    for (std::size_t i = 0; i < v.size() && i < other.size(); ++i)
      if (usable(other[i], os)) take(v[i]);
  }
  if (!x_axis) {
    for (const auto& h : p.hlines) take(h.y);
    for (const auto& f : p.fills)
      for (std::size_t i = 0; i < f.y_lo.size() && i < f.y_hi.size(); ++i) take(f.y_lo[i]), take(f.y_hi[i]);
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

ViewRange fit_range(const Panel& p, bool all) {
  const bool log_x = p.x_scale == Scale::Log, log_y = p.y_scale == Scale::Log;
  double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
  const bool framed = !all && p.fit_x1 > p.fit_x0 && (!log_x || p.fit_x0 > 0);
  std::vector<double> ys;  // the samples the y range is taken from
  for (const auto& s : p.series)
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!usable(s.x[i], p.x_scale) || !usable(s.y[i], p.y_scale)) continue;
      xmin = std::min(xmin, s.x[i]);
      xmax = std::max(xmax, s.x[i]);
      if (framed && (s.x[i] < p.fit_x0 || s.x[i] > p.fit_x1)) continue;
      ys.push_back(s.y[i]);
    }
  if (framed && xmax > xmin) {  // the frame, inside the data
    xmin = std::max(xmin, p.fit_x0);
    xmax = std::min(xmax, p.fit_x1);
  }
  if (!ys.empty()) {
    const double q = all ? 0.0 : std::clamp(p.fit_y_quantile, 0.0, 0.49);
    const auto lo = static_cast<std::size_t>(q * static_cast<double>(ys.size() - 1));
    const auto hi = ys.size() - 1 - lo;
    std::nth_element(ys.begin(), ys.begin() + static_cast<std::ptrdiff_t>(lo), ys.end());
    ymin = ys[lo];
    std::nth_element(ys.begin(), ys.begin() + static_cast<std::ptrdiff_t>(hi), ys.end());
    ymax = ys[hi];
  }
  if (!(xmax > xmin)) {
    xmin = log_x ? 1 : 0;
    xmax = 10;
  }
  if (!(ymax > ymin)) {
    ymin = log_y ? ymin * 0.5 : ymin - 1;
    ymax = log_y ? std::max(ymax, ymin) * 2 : ymax + 1;
    if (!std::isfinite(ymin) || !std::isfinite(ymax)) {
      ymin = log_y ? 1 : 0;
      ymax = 10;
    }
  }
  const auto fwd = [log_y](double v) { return log_y ? std::log10(std::max(v, 1e-300)) : v; };
  const auto inv = [log_y](double v) { return log_y ? std::pow(10.0, v) : v; };
  const double ly0 = fwd(ymin), ly1 = fwd(ymax), pad = 0.05 * (ly1 - ly0);
  return {xmin, xmax, inv(ly0 - pad), inv(ly1 + pad)};
}

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

namespace {
// The multiples `ms` of every decade inside [lo, hi].
std::vector<double> decade_multiples(double lo, double hi, const std::vector<double>& ms) {
  std::vector<double> out;
  if (!(hi > lo) || !(lo > 0) || !std::isfinite(hi)) return out;
  for (int e = static_cast<int>(std::floor(std::log10(lo)));
       e <= static_cast<int>(std::ceil(std::log10(hi))); ++e)
    for (double m : ms) {
      const double t = m * std::pow(10.0, e);
      if (t >= lo * (1 - 1e-12) && t <= hi * (1 + 1e-12)) out.push_back(t);
    }
  return out;
}
}  // namespace

std::vector<double> log_ticks(double lo, double hi, bool fine) {
  return fine ? decade_multiples(lo, hi, {1, 2, 5}) : decade_multiples(lo, hi, {1});
}

std::vector<double> log_minor_ticks(double lo, double hi) {
  return decade_multiples(lo, hi, {1, 2, 3, 4, 5, 6, 7, 8, 9});
}

AxisTicks axis_ticks(double lo, double hi, Scale s, double length_px, double label_px) {
  AxisTicks t;
  const double room = std::abs(length_px), spacing = std::max(1.5 * label_px, 24.0);
  const int fit = static_cast<int>(room / spacing);  // labels that fit along the axis
  if (s == Scale::Linear) {
    // At least three labels where the room allows (a 1-2-2.5-5 step can leave fewer).
    for (int target = std::clamp(fit, 3, 6); target <= std::max(6, fit); ++target) {
      t.major = linear_ticks(lo, hi, target);
      if (t.major.size() >= 3) break;
    }
    return t;
  }
  if (!(hi > lo) || !(lo > 0)) return t;
  // The finest labelling that fits: every multiple, 1-2-5, 1-3, decades.
  static const std::vector<std::vector<double>> kLabellings = {{1, 2, 3, 4, 5, 6, 7, 8, 9}, {1, 2, 5}, {1, 3}, {1}};
  for (const auto& ms : kLabellings) {
    t.major = decade_multiples(lo, hi, ms);
    if (static_cast<int>(t.major.size()) <= fit) break;
  }
  // Too many decades for their labels: every k-th decade (the rest stay grid).
  const double decades = std::log10(hi / lo);
  const std::vector<double> all = t.major;
  if (static_cast<int>(all.size()) > std::max(fit, 2)) {
    const auto k = static_cast<std::size_t>(std::ceil(static_cast<double>(all.size()) / std::max(fit, 2)));
    t.major.clear();
    for (std::size_t i = 0; i < all.size(); ++i) (i % k ? t.minor : t.major).push_back(all[i]);
  }
  if (room / std::max(decades, 1e-9) >= 40) {  // room for every multiple of a decade
    for (double v : log_minor_ticks(lo, hi))
      if (std::find(t.major.begin(), t.major.end(), v) == t.major.end()) t.minor.push_back(v);
    std::sort(t.minor.begin(), t.minor.end());
    t.minor.erase(std::unique(t.minor.begin(), t.minor.end()), t.minor.end());
  }
  return t;
}

std::string tick_label(double v, Scale s, const std::string& unit) {
  char b[48];
  if (s == Scale::Log && v > 0) {
    // SI prefixes for the usual ranges (Hz, ohm): 100, 1k, 20k, 1M.
    static constexpr std::pair<double, const char*> kPrefix[] = {
        {1e9, "G"},  {1e6, "M"},  {1e3, "k"},  {1.0, ""},
        {1e-3, "m"}, {1e-6, "u"}, {1e-9, "n"}, {1e-12, "p"}};
    for (const auto& [f, p] : kPrefix)
      if (v >= f * (1 - 1e-9)) {
        if (unit.empty())
          std::snprintf(b, sizeof b, "%g%s", v / f, p);
        else
          std::snprintf(b, sizeof b, "%g %s%s", v / f, p, unit.c_str());
        return b;
      }
  }
  std::snprintf(b, sizeof b, "%.6g", v);
  return unit.empty() ? std::string(b) : std::string(b) + " " + unit;
}

}  // namespace piezo::jobs::report
