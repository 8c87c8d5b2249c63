// GUI/report exports of a pipeline result: CSV in the project's
// f_hz,re_ohm,im_ohm form, Touchstone Z-format, and the JSON report.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "jobs/export/report_export.hpp"

using namespace piezo;

TEST(ReportExport, CsvTouchstoneAndJson) {
  jobs::PipelineResult r;
  r.capture_path = "x.h5";
  r.curves.push_back({"measured (Prony-SS)", {1000.0, 2000.0}, {{10.0, -20.0}, {5.0, -8.0}}});
  jobs::ParamRow p;
  p.name = "YE11";
  p.unit = "Pa";
  p.original = 6.3e10;
  p.updated = 6.66e10;
  p.sigma = 0.02e10;
  p.status = "ok";
  p.truth = 6.66e10;
  p.cmcm = 6.7e10;
  r.params.push_back(p);
  r.update_method = "output-error";
  r.stages.push_back({"update", true, "converged"});
  const auto dir = std::filesystem::temp_directory_path() / ("piezobench-export-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  jobs::export_csv(r, (dir / "a.csv").string());
  jobs::export_touchstone(r, (dir / "a.s1p").string());
  jobs::export_json(r, (dir / "a.json").string());
  std::ifstream csv(dir / "a.csv");
  std::string header, row;
  std::getline(csv, header);
  std::getline(csv, row);
  EXPECT_EQ(header, "f_hz,re_ohm,im_ohm");
  EXPECT_EQ(row.substr(0, 5), "1000,");
  std::ifstream s1p(dir / "a.s1p");
  std::stringstream ss;
  ss << s1p.rdbuf();
  EXPECT_NE(ss.str().find("# HZ Z RI R 50"), std::string::npos) << ss.str();
  std::ifstream js(dir / "a.json");
  auto j = nlohmann::json::parse(js);
  EXPECT_EQ(j["parameters"][0]["name"], "YE11");
  EXPECT_EQ(j["parameters"][0]["updated"], 6.66e10);
  EXPECT_EQ(j["parameters"][0]["sigma"], 0.02e10);  // issue 17: sigma beside every constant
  EXPECT_EQ(j["parameters"][0]["status"], "ok");
  EXPECT_EQ(j["parameters"][0]["cmcm"], 6.7e10);  // the seed's chain side by side
  EXPECT_EQ(j["update_method"], "output-error");
  EXPECT_EQ(j["stages"][0]["ran"], true);
  EXPECT_THROW(jobs::export_csv(r, (dir / "no/such/dir/a.csv").string()), std::runtime_error);
  jobs::PipelineResult empty;
  EXPECT_THROW(jobs::export_csv(empty, (dir / "b.csv").string()), std::runtime_error);
  std::filesystem::remove_all(dir);
}
