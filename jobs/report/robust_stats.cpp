#include "jobs/report/robust_stats.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace piezo::jobs::report {

namespace {
double median_of(std::vector<double> v) {
  const std::size_t n = v.size(), h = n / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(h), v.end());
  const double hi = v[h];
  if (n % 2) return hi;
  return 0.5 * (*std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(h)) + hi);
}
}  // namespace

RobustStats robust_stats(const std::vector<double>& values) {
  std::vector<double> v;
  for (double x : values)
    if (std::isfinite(x)) v.push_back(x);
  RobustStats s;
  s.n = v.size();
  if (v.empty()) return s;
  s.median = median_of(v);
  s.min = *std::min_element(v.begin(), v.end());
  s.max = *std::max_element(v.begin(), v.end());
  std::vector<double> dev;
  for (double x : v) dev.push_back(std::abs(x - s.median));
  s.mad = median_of(std::move(dev));
  return s;
}

double modified_z(double x, const RobustStats& s) {
  const double d = x - s.median;
  if (d == 0) return 0.0;
  if (s.mad == 0)
    return d > 0 ? std::numeric_limits<double>::infinity()
                 : -std::numeric_limits<double>::infinity();
  return 0.6745 * d / s.mad;
}

bool is_outlier(double x, const RobustStats& s) {
  return std::isfinite(x) && s.n >= kMinForOutliers &&
         std::abs(modified_z(x, s)) > kOutlierThreshold;
}

}  // namespace piezo::jobs::report
