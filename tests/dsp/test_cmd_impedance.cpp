// `piezobench impedance` end to end: a capture written with the analytic divider
// (lab exp_decay drive, 0.1 % noise) goes through every method and format.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "acquisition/capture_file.hpp"
#include "bvd_model.hpp"
#include "dsp/features.hpp"

namespace {
using namespace piezo;
namespace fs = std::filesystem;

struct Run {
  int code;
  std::string out;
};

Run run(const std::string& args) {
  const std::string cmd = std::string(PIEZO_CLI) + " " + args + " 2>/dev/null";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[4096];
  while (std::size_t n = fread(buf, 1, sizeof buf, p)) out.append(buf, n);
  const int st = pclose(p);
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, out};
}

class CmdImpedance : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("piezobench-imp-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    const auto m = bvd::tube_bvd_q(150);
    const auto resp = bvd::divider_response(m, 3140.0, 1.0, 3000.0);
    acq::Capture cap;
    cap.setup.divider_r1_ohm = 3140.0;
    for (int k = 0; k < 3; ++k) {
      acq::Shot s;
      s.sample_rate_hz = 1e7;
      s.excitation = acq::Excitation::ExpDecay;
      s.amplitude_v = 1.0;
      s.decay_per_s = 3000.0;
      s.pretrigger_samples = 200;
      s.v1 = bvd::add_noise(bvd::sample(resp.v1, 1e7, 20200, 200), 0.001, 10 + k);
      s.v2 = bvd::add_noise(bvd::sample(resp.v2, 1e7, 20200, 200), 0.001, 20 + k);
      cap.shots.push_back(s);
    }
    acq::write_capture(dir_ / "dut.h5", cap);
    truth_ = dsp::find_features([m](double f) { return m.impedance_at(f); }, 1e3, 120e3, 10.0);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string file() { return (dir_ / "dut.h5").string(); }
  static inline fs::path dir_;
  static inline dsp::ImpedanceFeatures truth_;
};

TEST_F(CmdImpedance, PronyJsonCarriesFeaturesOrderAndSingularValues) {
  const auto r = run("impedance " + file() + " --method prony --fmax 120e3 --step 100 --bootstrap 5 --json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["method"], "prony");
  EXPECT_EQ(j["samples_used"], 3000);
  EXPECT_NEAR(j["order"].get<double>(), 8.0, 2.0);
  EXPECT_DOUBLE_EQ(j["singular_values_normalized"][0].get<double>(), 1.0);
  ASSERT_EQ(j["resonances_hz"].size(), 3u);
  ASSERT_EQ(j["antiresonances_hz"].size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR(j["resonances_hz"][k].get<double>() / truth_.resonances[k].f_hz, 1.0, 2e-3);
    EXPECT_NEAR(j["antiresonances_hz"][k].get<double>() / truth_.antiresonances[k].f_hz, 1.0, 2e-3);
    EXPECT_GT(j["features"]["resonances_sigma_hz"][k].get<double>(), 0.0);
  }
  EXPECT_NEAR(j["capacitance_f"].get<double>() / truth_.capacitance_f, 1.0, 1e-2);
  EXPECT_TRUE(j.contains("rayleigh"));
  EXPECT_EQ(j["f_hz"].size(), j["re_ohm"].size());
  EXPECT_EQ(j["sigma_ohm"].size(), j["f_hz"].size());  // bootstrap σ per point
}

TEST_F(CmdImpedance, CsvAndTouchstone) {
  const auto c = run("impedance " + file() + " --method fft --fmax 120e3 --csv");
  ASSERT_EQ(c.code, 0);
  // the three columns first; the uncertainty band's columns follow (issue 10)
  EXPECT_EQ(c.out.rfind("f_hz,re_ohm,im_ohm,abs_ohm,abs_sigma_ohm,phase_deg,phase_sigma_deg,coverage_factor\n", 0), 0u);
  const auto s = run("impedance " + file() + " --method prony --fmax 120e3 --step 1000 --s1p");
  ASSERT_EQ(s.code, 0);
  EXPECT_NE(s.out.find("# HZ Z RI R 50\n"), std::string::npos);
}

TEST_F(CmdImpedance, CrossSpectraOverShots) {
  const auto r = run("impedance " + file() + " --method xspec --window rect --fmax 120e3 --json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["shots"].size(), 3u);
  EXPECT_TRUE(j.contains("coherence"));
  EXPECT_EQ(j["resonances_hz"].size(), 3u);
}

TEST_F(CmdImpedance, BadInputExitsTwo) {
  EXPECT_EQ(run("impedance " + (dir_ / "missing.h5").string() + " --json").code, 2);
  EXPECT_EQ(run("impedance " + file() + " --method magic").code, 2);
  EXPECT_EQ(run("impedance " + file() + " --method sine").code, 2);  // no sine shot
  EXPECT_EQ(run("impedance " + file() + " --order 5000 --json").code, 2);
  EXPECT_EQ(run("impedance " + file() + " --samples 99999").code, 2);
}

}  // namespace
