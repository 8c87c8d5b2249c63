// `piezobench instruments --json`: the registry's families as JSON (issue 20
// item 4), each with its roles, how it is chosen, and its simulated twin.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <set>

#include "tests/support/run_cli.hpp"

using namespace piezo;

TEST(CliInstruments, JsonListsEveryFamilyWithRolesAndTwins) {
  auto r = test::run_cli("instruments --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j["families"].is_array());
  std::set<std::string> keys;
  for (const auto& f : j["families"]) {
    keys.insert(f["key"].get<std::string>());
    EXPECT_FALSE(f["description"].get<std::string>().empty()) << f;
    EXPECT_FALSE(f["roles"].empty()) << f;
    EXPECT_FALSE(f["simulated_twin"].get<std::string>().empty()) << f;
    const auto by = f["chosen_by"].get<std::string>();
    EXPECT_TRUE(by == "*IDN?" || by == "address") << f;
    EXPECT_EQ(f.contains("address_form"), by == "address") << f;
  }
  EXPECT_EQ(keys, (std::set<std::string>{"keysight33500", "tektronix_awg", "infiniium", "redpitaya",
                                         "comedi"}));
  for (const auto& f : j["families"])
    if (f["key"] == "redpitaya") {
      EXPECT_EQ(f["roles"], nlohmann::json::array({"awg", "daq"}));
    }

  auto text = test::run_cli("instruments");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("comedi [daq]"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("chosen by its address: comedi:///dev/comediN?"), std::string::npos)
      << text.out;
}
