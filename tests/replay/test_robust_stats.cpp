// Median, MAD and the modified z-score outlier rule of the batch summary.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "jobs/report/robust_stats.hpp"

using namespace piezo::jobs::report;

TEST(RobustStats, MedianAndMadOddAndEven) {
  auto s = robust_stats({3, 1, 2, 100, 4});
  EXPECT_EQ(s.n, 5u);
  EXPECT_EQ(s.median, 3.0);
  EXPECT_EQ(s.mad, 1.0);  // |dev| = 0,2,1,97,1 → median 1
  EXPECT_EQ(s.min, 1.0);
  EXPECT_EQ(s.max, 100.0);
  auto e = robust_stats({4, 1, 3, 2});
  EXPECT_EQ(e.median, 2.5);
  EXPECT_EQ(e.mad, 1.0);  // |dev| = 1.5,1.5,0.5,0.5
}

TEST(RobustStats, NonFiniteValuesAreIgnored) {
  auto s = robust_stats({1, std::nan(""), 2, std::numeric_limits<double>::infinity(), 3});
  EXPECT_EQ(s.n, 3u);
  EXPECT_EQ(s.median, 2.0);
}

TEST(RobustStats, OutlierRule) {
  auto s = robust_stats({10.0, 10.1, 9.9, 10.05, 9.95, 13.0});
  // median 10.025, MAD 0.075: 13 has M = 0.6745·2.975/0.075 ≈ 26.8, 10.1 has ≈ 0.67.
  EXPECT_NEAR(modified_z(13.0, s), 0.6745 * (13.0 - 10.025) / 0.075, 1e-9);
  EXPECT_TRUE(is_outlier(13.0, s));
  EXPECT_FALSE(is_outlier(10.1, s));
  EXPECT_FALSE(is_outlier(std::nan(""), s));
  // Too few values: nothing is flagged.
  auto few = robust_stats({1.0, 1.0, 50.0});
  EXPECT_FALSE(is_outlier(50.0, few));
  // MAD = 0: anything off the median is infinitely far.
  auto flat = robust_stats({5, 5, 5, 5, 6});
  EXPECT_EQ(flat.mad, 0.0);
  EXPECT_TRUE(std::isinf(modified_z(6, flat)));
  EXPECT_TRUE(is_outlier(6, flat));
  EXPECT_FALSE(is_outlier(5, flat));
}
