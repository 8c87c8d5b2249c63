// `piezobench impedance` end to end: a capture written with the analytic divider
// (lab exp_decay drive, 0.1 % noise) goes through every method and format.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
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
  // The one estimate's record length (acq::kDefaultEstimateSamples), as the pipeline's.
  EXPECT_EQ(j["samples_used"], 6000);
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

// Per-mode figures (issue 19): "modes" in --json, against the capture's own BVD network.
TEST_F(CmdImpedance, PronyJsonCarriesModeFigures) {
  const auto r = run("impedance " + file() + " --method prony --fmax 120e3 --step 50 --bootstrap 5 --json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j.contains("modes"));
  ASSERT_EQ(j["modes"].size(), 3u);
  const auto m = bvd::tube_bvd_q(150);
  for (std::size_t k = 0; k < 3; ++k) {
    const auto& b = m.branches[k];
    const auto& x = j["modes"][k];
    const double fs = 1 / (2 * M_PI * std::sqrt(b.L * b.C));
    const double fp = fs * std::sqrt(1 + b.C / m.c0);
    const double q = 1 / (2 * M_PI * fs * b.R * b.C);
    const double k2 = b.C / (m.c0 + b.C);
    const double qbw = x["qm_bandwidth"].is_number() ? x["qm_bandwidth"].get<double>() : -1.0;
    std::printf("mode %zu: fs %.2f (true %.2f), fp %.2f (%.2f), k_eff2 %.5f (%.5f), Qm %.1f / %.1f (%.1f), "
                "R1 %.3f (%.3f), C1 %.5g (%.5g), C0 %.5g (%.5g)\n",
                k, x["fs_hz"].get<double>(), fs, x["fp_hz"].get<double>(), fp, x["k_eff2"].get<double>(), k2,
                x["qm_branch"].get<double>(), qbw, q, x["r1_ohm"].get<double>(), b.R, x["c1_f"].get<double>(),
                b.C, x["c0_f"].get<double>(), m.c0);
    // What the figures can be is what the estimate is: Prony-SS on 3000 samples (0.3 ms)
    // of a Q = 150 network whose modes ring for ~1 ms reads the frequencies to 3e-4 but
    // the damping only to 10-15 % (measured: fs −3e-4…+2e-4, fp −1e-3…−6e-4, k_eff² −4 %…−0.5 %,
    // Qm from the branch +11…+14 % on modes 1–2, −12 % on mode 3, from the bandwidth +3…+5 %,
    // C0 −0.5…+3 %); tolerances about twice those.
    EXPECT_NEAR(x["fs_hz"].get<double>() / fs, 1.0, 1e-3) << k;
    EXPECT_NEAR(x["fp_hz"].get<double>() / fp, 1.0, 2e-3) << k;
    EXPECT_NEAR(x["k_eff2"].get<double>() / k2, 1.0, 8e-2) << k;
    EXPECT_NEAR(x["qm_branch"].get<double>() / q, 1.0, 0.3) << k;
    EXPECT_NEAR(qbw / q, 1.0, 0.1) << k;
    EXPECT_NEAR(x["c0_f"].get<double>() / m.c0, 1.0, 6e-2) << k;
    EXPECT_GT(x["c1_sigma_f"].get<double>(), 0.0);
  }
  const auto& s = j["mode_summary"];
  EXPECT_EQ(s["reference_hz"].get<double>(), 1000.0);
  EXPECT_NEAR(s["free_capacitance_f"].get<double>() / m.static_capacitance(), 1.0, 1e-2);
  EXPECT_EQ(s["hoop_mode"].get<int>(), 2);  // 79.4/95.1 kHz: the most strongly coupled
  EXPECT_EQ(j["method"], "prony");          // the existing fields stay
}

// On the FFT's 500 Hz bins (20 000 samples at 10 MS/s) the Q = 150 resonances (335 Hz
// wide) are not resolved: the table still prints, with notes instead of numbers.
TEST_F(CmdImpedance, FiguresTableInTextEvenOnACoarseGrid) {
  const auto r = run("impedance " + file() + " --method fft --fmax 120e3 --figures");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("mode figures"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("C^T"), std::string::npos);
  EXPECT_NE(r.out.find("note:"), std::string::npos);
  std::printf("%s", r.out.c_str());
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
