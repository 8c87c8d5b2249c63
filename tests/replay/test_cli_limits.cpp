// `piezobench replay --limits` end to end on five simulated captures (four
// tubes whose Young's modulus differs, one truncated file): pass / fail /
// error per capture with the reasons in the JSON lines and the results file,
// the lot summary in --json and in the report folder, the stored verdicts
// following a new limits file on resume, and a malformed limits file refused
// before any capture is replayed.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>

#include "tests/replay/replay_test_support.hpp"

using namespace piezo;
namespace fs = std::filesystem;

namespace {

// The simulated tubes: YE11 → the verdict expected against kLimits.
// 6.2e10 is below the YE11 range, 7.1e10 above it and its fs of the first
// mode (≈ 53.0 kHz) above 52.5 kHz; the other two pass (fs ≈ 51.7, 51.8 kHz).
const std::map<std::string, std::string> kExpected = {{"T-a.h5", "fail"},
                                                      {"T-b.h5", "pass"},
                                                      {"T-c.h5", "pass"},
                                                      {"T-d.h5", "fail"},
                                                      {"T-bad.h5", "error"}};
const std::map<std::string, double> kYe11 = {
    {"T-a.h5", 6.2e10}, {"T-b.h5", 6.66e10}, {"T-c.h5", 6.70e10}, {"T-d.h5", 7.1e10}};

const char* kLimits = R"([lot]
name = "test lot"

[[limit]]
quantity = "parameters.YE11"
unit = "Pa"
min = 6.4e10
max = 6.9e10

[[limit]]
quantity = "modes[fs_hz=45e3..54e3].fs_hz"
label = "fs, mode 1"
unit = "Hz"
max = 52.5e3

[[limit]]
quantity = "mode_summary.free_capacitance_f"
min = 1.0e-8
max = 2.0e-8

[[limit]]
quantity = "diagnosis.verdict_effect"
allowed = ["none"]
)";

void write(const fs::path& f, const std::string& text) { std::ofstream(f) << text; }

}  // namespace

TEST(CliLimits, PassFailAndErrorPerCaptureAndTheLotSummary) {
  const auto dir = test::fresh_dir("replay-limits");
  const fs::path in = dir / "captures";
  int seed = 21;
  for (const auto& [name, ye] : kYe11) test::make_capture(in / name, ye, seed++);
  test::make_truncated_capture(in / "T-bad.h5");
  const fs::path limits = dir / "limits.toml", out = dir / "r.h5", jsonl = dir / "r.jsonl",
                 rep = dir / "report";
  write(limits, kLimits);
  auto r = test::run_cli("replay '" + in.string() + "' --jobs 2 --out '" + out.string() +
                         "' --jsonl '" + jsonl.string() + "' --report '" + rep.string() +
                         "' --limits '" + limits.string() + "' --json");
  ASSERT_EQ(r.exit_code, 2)
      << r.err;  // the truncated capture was refused; failing limits are not errors
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j.contains("lot")) << r.out;
  const auto& lot = j["lot"];
  EXPECT_EQ(lot["captures"], 5);
  EXPECT_EQ(lot["pass"], 2);
  EXPECT_EQ(lot["fail"], 2);
  EXPECT_EQ(lot["error"], 1);
  EXPECT_EQ(lot["name"], "test lot");

  // Each JSON line carries its verdict; the YE11 values give the capability by hand.
  std::vector<double> ye;
  for (const auto& line : test::read_lines(jsonl)) {
    const std::string name = fs::path(line["path"].get<std::string>()).filename();
    ASSERT_TRUE(line.contains("limits")) << name;
    EXPECT_EQ(line["limits"]["status"], kExpected.at(name))
        << name << ": " << line["limits"].dump();
    EXPECT_EQ(line["limits"]["file"], limits.string());
    if (name == "T-a.h5") {
      ASSERT_EQ(line["limits"]["reasons"].size(), 1u);
      EXPECT_EQ(line["limits"]["reasons"][0].get<std::string>().rfind("parameters.YE11 = 6.", 0),
                0u);
      EXPECT_NE(line["limits"]["reasons"][0].get<std::string>().find("< min 6.4e+10 Pa"),
                std::string::npos);
    }
    if (name == "T-d.h5") {
      ASSERT_EQ(line["limits"]["reasons"].size(), 2u) << line["limits"].dump();
      EXPECT_NE(line["limits"]["reasons"][0].get<std::string>().find("> max 6.9e+10 Pa"),
                std::string::npos);
      EXPECT_NE(line["limits"]["reasons"][1].get<std::string>().find("> max 52500 Hz"),
                std::string::npos);
    }
    if (name == "T-bad.h5") {
      EXPECT_EQ(line["limits"]["reasons"][0].get<std::string>().rfind("replay failed: ", 0), 0u);
    } else {
      ye.push_back(line["result"]["parameters"][0]["updated"].get<double>());
    }
  }
  ASSERT_EQ(ye.size(), 4u);
  double mean = 0, ss = 0;
  for (double x : ye) mean += x / 4;
  for (double x : ye) ss += (x - mean) * (x - mean);
  const double sd = std::sqrt(ss / 3);
  const auto& q = lot["quantities"][0];
  EXPECT_EQ(q["quantity"], "parameters.YE11");
  EXPECT_EQ(q["n"], 4);
  EXPECT_EQ(q["below_min"], 1);
  EXPECT_EQ(q["above_max"], 1);
  EXPECT_NEAR(q["mean"].get<double>(), mean, 1e-6 * mean);
  EXPECT_NEAR(q["sd"].get<double>(), sd, 1e-9 * sd);
  EXPECT_NEAR(q["cpk"].get<double>(), std::min(6.9e10 - mean, mean - 6.4e10) / (3 * sd), 1e-9);
  EXPECT_EQ(lot["quantities"][1]["above_max"], 1);
  EXPECT_EQ(lot["quantities"][3]["values"]["none"], 4);

  // The results file holds the same verdicts; the report folder the lot report.
  std::size_t stored = 0;
  acq::for_each_result(out, [&](const acq::ResultRecord& rec) {
    const auto rj = nlohmann::json::parse(rec.result_json);
    ASSERT_TRUE(rj.contains("limits")) << rec.input_path;
    EXPECT_EQ(rj["limits"]["status"], kExpected.at(fs::path(rec.input_path).filename()))
        << rec.input_path;
    ++stored;
  });
  EXPECT_EQ(stored, 5u);
  for (const char* f :
       {"lot.md", "lot.json", "lot_histograms.svg", "lot_histograms.png", "summary.md"})
    EXPECT_TRUE(fs::is_regular_file(rep / f)) << f;
  std::ifstream lj(rep / "lot.json");
  EXPECT_EQ(nlohmann::json::parse(lj), lot);

  // Resumed with wider YE11 limits: nothing is replayed again, the stored verdicts follow the new
  // file.
  std::string wider = kLimits;
  wider.replace(wider.find("max = 6.9e10"), 12, "max = 7.2e10");
  const fs::path limits2 = dir / "limits2.toml";
  write(limits2, wider);
  auto r2 = test::run_cli("replay '" + in.string() + "' --out '" + out.string() + "' --limits '" +
                          limits2.string() + "' --json");
  ASSERT_EQ(r2.exit_code, 2) << r2.err;  // the truncated capture stays refused
  const auto j2 = nlohmann::json::parse(r2.out);
  EXPECT_EQ(j2["replayed"], 0);
  EXPECT_EQ(j2["lot"]["pass"], 2);
  EXPECT_EQ(j2["lot"]["fail"], 2);  // T-d.h5 still fails, on fs alone now
  acq::for_each_result(out, [&](const acq::ResultRecord& rec) {
    const auto rj = nlohmann::json::parse(rec.result_json);
    EXPECT_EQ(rj["limits"]["file"], limits2.string());
    if (fs::path(rec.input_path).filename() == "T-d.h5") {
      ASSERT_EQ(rj["limits"]["reasons"].size(), 1u);
      EXPECT_NE(rj["limits"]["reasons"][0].get<std::string>().find("> max 52500 Hz"),
                std::string::npos);
    }
  });
}

TEST(CliLimits, AMalformedLimitsFileIsRefusedBeforeAnyCapture) {
  const auto dir = test::fresh_dir("replay-limits-bad");
  test::make_capture(dir / "captures" / "T.h5", 6.66e10, 5);
  const fs::path limits = dir / "limits.toml", out = dir / "r.h5";
  write(limits, "[[limit]]\nquantity = \"parameters.YE11\"\nmin = 7e10\nmax = 6e10\n");
  auto r = test::run_cli("replay '" + (dir / "captures").string() + "' --out '" + out.string() +
                         "' --limits '" + limits.string() + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(
      r.err.find("--limits: " + limits.string() + ":1: parameters.YE11: min 7e+10 > max 6e+10"),
      std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(out));

  write(limits, "[[limit]]\nquantity = \"x\"\nmin = 1\nmaxx = 2\n");
  r = test::run_cli("replay '" + (dir / "captures").string() + "' --out '" + out.string() +
                    "' --limits '" + limits.string() + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(limits.string() + ":4: maxx: unknown key"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}
