#pragma once
// Robust location and spread of one parameter across many transducers, and
// the outlier rule of the batch summary: the modified z-score
// M = 0.6745·(x − median)/MAD (Iglewicz & Hoaglin, 1993), |M| > 3.5 flagged.
// Median and MAD ignore a few wild values that would inflate a mean and a
// standard deviation and hide the very outliers we look for.
#include <cstddef>
#include <vector>

namespace piezo::jobs::report {

struct RobustStats {
  std::size_t n = 0;  // finite values used
  double median = 0, mad = 0, min = 0, max = 0;
};

inline constexpr double kOutlierThreshold = 3.5;
inline constexpr std::size_t kMinForOutliers = 4;  // fewer values: no outlier is flagged

RobustStats robust_stats(const std::vector<double>& values);  // non-finite values are ignored
// 0 when x equals the median; ±infinity when MAD is 0 and x differs.
double modified_z(double x, const RobustStats& s);
bool is_outlier(double x, const RobustStats& s);

}  // namespace piezo::jobs::report
