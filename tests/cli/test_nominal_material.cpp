// Issue 18, item 4: a capture's /setup/material that is a description, or
// nothing, never fails a capture (jobs/nominal_material.hpp); the CLI's
// `update CAP.h5` and `replay` use it.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "acquisition/capture_file.hpp"
#include "tests/support/run_cli.hpp"
#include "jobs/nominal_material.hpp"

namespace fs = std::filesystem;
using piezo::jobs::nominal_material;

TEST(NominalMaterial, TheUsersChoiceWinsAndMustBeAPreset) {
  const auto m = nominal_material("PZT-5H", std::string("apc850"));
  EXPECT_EQ(m.name, "pzt5h");
  EXPECT_FALSE(m.warning);
  EXPECT_THROW(nominal_material("unobtainium", std::string("apc850")), std::invalid_argument);
}

TEST(NominalMaterial, APresetNameIsUsedSilently) {
  const auto m = nominal_material("", std::string("APC-850"));
  EXPECT_EQ(m.name, "apc850");
  EXPECT_FALSE(m.warning);
}

TEST(NominalMaterial, ADescriptionNamingPresetsUsesTheFirstWithAWarning) {
  const auto m = nominal_material("", std::string("PZT-5A class (APC850) radially poled tube"));
  EXPECT_EQ(m.name, "apc850");  // material_presets() order: apc850 before pzt5a
  ASSERT_TRUE(m.warning);
  EXPECT_NE(m.warning->find("pzt5a"), std::string::npos) << *m.warning;
  EXPECT_NE(m.warning->find("--material"), std::string::npos) << *m.warning;
  EXPECT_EQ(nominal_material("", std::string("a Navy type II (PZT-5A) tube")).name, "pzt5a");
}

TEST(NominalMaterial, NoneOrAnUnknownOneFallsBackToTheSeedsWithAWarningNamingTheOption) {
  for (const auto& text : {std::optional<std::string>{}, std::optional<std::string>{""},
                           std::optional<std::string>{"lead titanate, unknown vendor"}}) {
    const auto m = nominal_material("", text);
    EXPECT_EQ(m.name, "apc850");
    ASSERT_TRUE(m.warning);
    EXPECT_NE(m.warning->find("--material"), std::string::npos) << *m.warning;
  }
}

// The same through the CLI, on a real capture whose material is a description.
TEST(NominalMaterial, UpdateOfACaptureWithADescriptionRunsAndSaysWhichPresetItUsed) {
  const fs::path dir = fs::temp_directory_path() / ("piezobench-material-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  auto cap = piezo::acq::read_capture(std::string(PIEZO_SOURCE_DIR) + "/fixtures/h5py-bvd-exp-decay.h5");
  cap.setup.material = "PZT-5A class (APC850) radially poled tube";
  const fs::path file = dir / "described.h5";
  piezo::acq::write_capture(file, cap);
  const auto r = piezo::test::run_cli("update " + file.string() + " --method oe --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["material"], "apc850");
  ASSERT_TRUE(j.contains("warnings"));
  EXPECT_NE(j["warnings"].dump().find("named in it"), std::string::npos) << j["warnings"].dump();
  EXPECT_NE(r.err.find("--material"), std::string::npos) << r.err;
  fs::remove_all(dir);
}
