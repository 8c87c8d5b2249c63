// `piezobench model mode-shape-cmcm`: JSON field names, the exact mode-shape
// answer through the CLI, and the exit codes (bad input 2, failed update 1).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "tests/support/run_cli.hpp"

namespace {

using piezo::test::run_cli;

TEST(CliModeShape, JsonFieldsAndTheExactAnswer) {
  const auto r = run_cli("model mode-shape-cmcm --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["rows"].size(), 10u);
  for (const auto& row : j["rows"])
    for (const char* k : {"name", "target", "mode_shape_cmcm", "extended_cmcm", "output_error"})
      EXPECT_TRUE(row.contains(k)) << k;
  EXPECT_TRUE(j["mode_shape_cmcm"]["ok"].get<bool>());
  EXPECT_EQ(j["mode_shape_cmcm"]["systems"][0]["rank"].get<int>(), 11);
  // The elastic constants are exact from exact shapes (test_mode_shape_cmcm: 1e-8).
  for (int k = 0; k < 5; ++k) {
    const auto& row = j["rows"][static_cast<std::size_t>(k)];
    EXPECT_NEAR(row["mode_shape_cmcm"].get<double>() / row["target"].get<double>(), 1, 1e-8)
        << row["name"].get<std::string>();
  }
  for (const char* who : {"original", "target", "mode_shape_cmcm", "extended_cmcm", "output_error"})
    EXPECT_EQ(j["frequencies"][who]["resonances_hz"].size(), 3u) << who;
  EXPECT_EQ(j["extended_cmcm"]["status"].get<std::string>(), "converged");
}

TEST(CliModeShape, ExitCodes) {
  EXPECT_EQ(run_cli("model mode-shape-cmcm --staging sideways").exit_code, 2);
  EXPECT_EQ(run_cli("model mode-shape-cmcm --capture-noise -1").exit_code, 2);
  // The seed's staging fails on our model (docs/update-methods.md, Appendix D): exit 1.
  EXPECT_EQ(run_cli("model mode-shape-cmcm --staging seed").exit_code, 1);
}

}  // namespace
