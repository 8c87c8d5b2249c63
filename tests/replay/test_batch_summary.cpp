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
  EXPECT_EQ(s.distributions[2].name, "f_r1 (estimate order)");  // no per-mode figures in these records
  EXPECT_EQ(s.distributions[0].stats.n, 6u);
  ASSERT_EQ(s.distributions[0].outliers.size(), 1u);
  EXPECT_EQ(s.entries[s.distributions[0].outliers[0]].path, "line/T-005.h5");
  EXPECT_TRUE(s.distributions[1].outliers.empty());  // all equal: MAD 0, nobody off the median
  const std::string md = batch_summary_markdown(s, "R.h5");
  EXPECT_NE(md.find("7 (6 replayed, 1 failed)"), std::string::npos) << md;
  EXPECT_NE(md.find("line/bad.h5: /: truncated"), std::string::npos);
  EXPECT_NE(md.find("| [line/T-005.h5](captures/line-T-005-k5/summary.md) | YE11 |"), std::string::npos)
      << md;
  EXPECT_EQ(distributions_figure(s).panels.size(), s.distributions.size());
}

TEST(BatchSummary, ReportFolderNamesAreSafeAndUnique) {
  // The folder it sits in names the case or tube (refsim-v1/05/fit.h5 → 05-fit).
  EXPECT_EQ(capture_report_folder("a b/T:1.h5", "0123456789abcdef"), "captures/a_b-T_1-01234567");
  EXPECT_EQ(capture_report_folder("corpus/05/fit.h5", "d019240d11"), "captures/05-fit-d019240d");
  EXPECT_EQ(capture_report_folder("T.h5", "0123456789"), "captures/T-01234567");
  EXPECT_NE(capture_report_folder("x/T.h5", "aaaaaaaa11"),
            capture_report_folder("y/T.h5", "bbbbbbbb11"));
}

// Issue 41 item 3: frequency columns per identified mode (the per-mode
// figures' modes, the updated model's), never the estimate's raw feature
// order: a capture whose estimate found a spurious low "resonance" first
// still files its first radial mode under mode 1; an unreliable mode is left out.
TEST(BatchSummary, FrequencyColumnsPerIdentifiedMode) {
  auto rec = [](double spurious, const char* status2) {
    nlohmann::json r = {{"parameters", nlohmann::json::array()},
                        {"resonances_hz", {spurious, 50e3, 80e3}},
                        {"antiresonances_hz", {52e3}},
                        {"modes",
                         {{{"fs_hz", 50e3}, {"fp_hz", 53e3}, {"status", "ok"}},
                          {{"fs_hz", 80e3}, {"fp_hz", 81e3}, {"status", status2}}}},
                        {"verdict", ""}};
    return nlohmann::json{{"path", "p.h5"}, {"sha256", "00"}, {"status", "ok"}, {"result", r}};
  };
  const auto a = batch_entry("a", rec(16e3, "ok"));
  const auto b = batch_entry("b", rec(84e3, "unreliable"));
  ASSERT_NE(a.find("fs_mode1"), nullptr);
  EXPECT_DOUBLE_EQ(a.find("fs_mode1")->value, 50e3);
  EXPECT_DOUBLE_EQ(b.find("fs_mode1")->value, 50e3);
  EXPECT_DOUBLE_EQ(a.find("fp_mode2")->value, 81e3);
  EXPECT_EQ(b.find("fs_mode2"), nullptr);
  EXPECT_EQ(a.find("f_r1 (estimate order)"), nullptr);
}
