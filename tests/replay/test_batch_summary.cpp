// The batch summary: entries from replay records, distributions, the outlier
// flag on a transducer that differs, failed captures listed.
#include <gtest/gtest.h>

#include "jobs/report/batch_summary.hpp"

using namespace piezo::jobs::report;

namespace {
nlohmann::json ok_record(const std::string& path, double ye11, double f1) {
  nlohmann::json r = {{"parameters",
                       {{{"name", "YE11"}, {"unit", "Pa"}, {"original", 6.3e10}, {"updated", ye11}},
                        {{"name", "nu12"}, {"unit", "-"}, {"original", 0.31}, {"updated", 0.333}}}},
                      {"resonances_hz", {f1, 2 * f1}},
                      {"antiresonances_hz", {1.01 * f1}},
                      {"verdict", ""}};
  return {{"path", path}, {"sha256", "00"}, {"status", "ok"}, {"result", r}};
}
}  // namespace

TEST(BatchSummary, DistributionsOutliersAndFailures) {
  std::vector<BatchEntry> e;
  const double ye[] = {6.66e10, 6.67e10, 6.65e10, 6.66e10, 6.68e10, 5.9e10};
  const char* digits = "012345";
  for (int k = 0; k < 6; ++k) {
    const std::string n(1,
                        digits[k]);  // (GCC 12 warns falsely on "x" + std::to_string(k) + "y" here)
    e.push_back(batch_entry("k" + n, ok_record("line/T-00" + n + ".h5", ye[k], 50e3 + k)));
  }
  e.push_back(batch_entry(
      "kbad", {{"path", "line/bad.h5"},
               {"sha256", "11"},
               {"status", "failed"},
               {"error", {{"kind", "bad capture"}, {"message", "line/bad.h5: /: truncated"}}}}));
  auto s = summarize(e);
  EXPECT_EQ(s.ok, 6u);
  EXPECT_EQ(s.failed, 1u);
  ASSERT_GE(s.distributions.size(), 4u);
  // Parameters first in the pipeline's order, then the features.
  EXPECT_EQ(s.distributions[0].name, "YE11");
  EXPECT_EQ(s.distributions[0].unit, "Pa");
  EXPECT_EQ(s.distributions[1].name, "nu12");
  EXPECT_EQ(s.distributions[2].name, "f_r1");
  EXPECT_EQ(s.distributions[0].stats.n, 6u);
  ASSERT_EQ(s.distributions[0].outliers.size(), 1u);
  EXPECT_EQ(s.entries[s.distributions[0].outliers[0]].path, "line/T-005.h5");
  EXPECT_TRUE(s.distributions[1].outliers.empty());  // all equal: MAD 0, nobody off the median
  const std::string md = batch_summary_markdown(s, "R.h5");
  EXPECT_NE(md.find("7 (6 replayed, 1 failed)"), std::string::npos) << md;
  EXPECT_NE(md.find("line/bad.h5: /: truncated"), std::string::npos);
  EXPECT_NE(md.find("| [line/T-005.h5](captures/T-005-k5/summary.md) | YE11 |"), std::string::npos)
      << md;
  EXPECT_EQ(distributions_figure(s).panels.size(), s.distributions.size());
}

TEST(BatchSummary, ReportFolderNamesAreSafeAndUnique) {
  EXPECT_EQ(capture_report_folder("a b/T:1.h5", "0123456789abcdef"), "captures/T_1-01234567");
  EXPECT_NE(capture_report_folder("x/T.h5", "aaaaaaaa11"),
            capture_report_folder("y/T.h5", "bbbbbbbb11"));
}
