// `piezobench model …` end to end: JSON shape of `model modal`, CSV of
// `model impedance`, exit code 2 on bad input.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

namespace {
struct Run {
  int code;
  std::string out;
};
Run run(const std::string& args) {
  const std::string cmd = std::string(PIEZO_CLI) + " " + args + " 2>/dev/null";
  std::unique_ptr<FILE, int (*)(FILE*)> p(popen(cmd.c_str(), "r"), pclose);
  std::string out;
  std::array<char, 4096> buf{};
  std::size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p.get())) > 0) out.append(buf.data(), n);
  const int status = pclose(p.release());
  return {WEXITSTATUS(status), out};
}
}  // namespace

TEST(CmdModel, ModalJsonListsTheActiveModes) {
  auto r = run("model modal --material apc850 --isotropic "
               "--set YE11=6.66e10,nu12=0.3333,d31=-210e-12,epsT33_rel=2294 --modes 10 --json");
  ASSERT_EQ(r.code, 0) << r.out;
  auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["short_circuit_hz"].size(), 3u);
  ASSERT_EQ(j["open_circuit_hz"].size(), 3u);
  EXPECT_EQ(j["modes"].size(), 20u);
  // Tables 4/5 targets within 1 %.
  const double res[3] = {51400, 55000, 82600}, anti[3] = {52400, 55800, 101600};
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(j["short_circuit_hz"][i].get<double>() / res[i], 1.0, 1e-2);
    EXPECT_NEAR(j["open_circuit_hz"][i].get<double>() / anti[i], 1.0, 1e-2);
  }
}

TEST(CmdModel, ImpedanceCsv) {
  auto r = run("model impedance --material apc850 --fmin 1000 --fmax 3000 --step 1000 "
               "--rayleigh-beta 1e-7 --csv");
  ASSERT_EQ(r.code, 0);
  EXPECT_EQ(r.out.rfind("f_hz,re_ohm,im_ohm\n", 0), 0u);
  int lines = 0;
  for (char c : r.out) lines += c == '\n';
  EXPECT_EQ(lines, 4);
}

TEST(CmdModel, BadInputExitsTwo) {
  EXPECT_EQ(run("model modal --material unobtainium --json").code, 2);
  EXPECT_EQ(run("model modal --isotropic --set sE33=1e-11").code, 2);
  EXPECT_EQ(run("model impedance --fmin 10 --fmax 5 --step 1").code, 2);
}

TEST(CmdModel, SensitivityJsonHasEveryConstantTwice) {
  auto r = run("model sensitivity --material apc850 --json");
  ASSERT_EQ(r.code, 0) << r.out;
  auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["cases"].size(), 20u);  // 10 d-form constants × {2, 0.5}
  EXPECT_EQ(j["nominal"]["short_circuit_hz"].size(), 3u);
  EXPECT_EQ(j["band_hz"].get<double>(), 200e3);
  EXPECT_TRUE(j["converged"].get<bool>());
  for (const auto& c : j["cases"]) {
    if (c["valid"].get<bool>()) {
      EXPECT_EQ(c["short_circuit"].size(), 3u);
      EXPECT_TRUE(c.contains("c_static_change"));
    } else {
      EXPECT_FALSE(c["reason"].get<std::string>().empty());
    }
  }
  // εT33 doubled doubles C_static (within 1 %).
  EXPECT_NEAR(j["cases"][18]["c_static_change"].get<double>(), 1.0, 0.01);
  EXPECT_EQ(run("model sensitivity --band -5").code, 2);
}

TEST(CmdModel, SensitivitySeedProtocolFlagsWhatItSolvesOutsideThePhysicalDomain) {
  auto r = run("model sensitivity --material apc850 --form e --seed-protocol --json");
  ASSERT_EQ(r.code, 0) << r.out;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["form"], "e");
  EXPECT_TRUE(j["seed_protocol"].get<bool>());
  ASSERT_EQ(j["cases"].size(), 10u);  // the seed's factor only: elastic x2, piezoelectric and dielectric x0.5
  int flagged = 0;
  for (const auto& c : j["cases"]) {
    EXPECT_TRUE(c["solved"].get<bool>()) << c.dump();
    if (!c["physical"].get<bool>()) {
      ++flagged;
      EXPECT_FALSE(c["valid"].get<bool>());
      EXPECT_FALSE(c["reason"].get<std::string>().empty());
    }
  }
  EXPECT_EQ(flagged, 1);  // cE13 doubled: cE not positive definite
  EXPECT_EQ(run("model sensitivity --form q").code, 2);
}

TEST(CmdModel, ThreeDJsonHasTable3TorsionAndTheHarmonics) {
  // Issue 44 items 1: Table 3's 3-D column (harmonic 0 against the 2-D code),
  // the exact torsion, the harmonics' modes, Fig 17's comparison.
  auto r = run("model three-d --max-n 2 --fmax 60000 --step 1000 --json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["table3"].size(), 6u);
  for (const auto& row : j["table3"]) EXPECT_LT(std::abs(row["relative_difference"].get<double>()), 1e-9);
  ASSERT_GE(j["torsion_check"].size(), 1u);
  EXPECT_LT(std::abs(j["torsion_check"][0]["relative_difference"].get<double>()), 1e-5);
  ASSERT_EQ(j["harmonics"].size(), 4u);  // n = 0 cos, n = 0 sin, n = 1, n = 2
  EXPECT_EQ(j["harmonics"][2]["rigid_motions"].get<int>(), 2);
  for (const auto& m : j["harmonics"][3]["modes"]) EXPECT_FALSE(m["electrically_active"].get<bool>());
  // The 2-D port model (20 modes + residual) and the 3-D one (all modes) on
  // a 1 kHz grid that misses the extrema: equal within 0.05 dB.
  EXPECT_LT(j["fig17"]["three_d_vs_two_d"]["max_abs_db"].get<double>(), 0.05);
}

TEST(CmdModel, ConstrainedCsvAndBadPlotName) {
  auto r = run("model constrained --fmin 1000 --fmax 3000 --step 1000 --csv");
  ASSERT_EQ(r.code, 0);
  EXPECT_EQ(r.out.rfind("f_hz,free_fe_abs_ohm,constrained_fe_abs_ohm,ring_abs_ohm\n", 0), 0u) << r.out;
  EXPECT_EQ(run("model constrained --fmin 1000 --fmax 3000 --step 1000 --plot fig19.txt").code, 2);
  EXPECT_EQ(run("model three-d --max-n 99").code, 2);
}

// Appendix A (`model bar`): IEEE Std 176 reads the material's coupling back
// from the first free-free pair, the 31 bar resonates at c/(2L), a fixed-free
// bar at a quarter wave; bad input is exit code 2.
TEST(CmdModel, BarAppendixA) {
  auto r = run("model bar --mode 31 --length 0.02 --json");
  ASSERT_EQ(r.code, 0) << r.out;
  auto j = nlohmann::json::parse(r.out);
  ASSERT_GE(j["pairs"].size(), 1u);
  EXPECT_NEAR(j["ieee176_k"].get<double>() / j["k_material"].get<double>(), 1.0, 1e-8);
  const double c = j["wave_speed_m_s"].get<double>();
  EXPECT_NEAR(j["pairs"][0]["resonance_hz"].get<double>() / (c / 0.04), 1.0, 1e-10);
  r = run("model bar --mode 33 --ends fixed-mass --length 0.02 --json");
  ASSERT_EQ(r.code, 0) << r.out;
  j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["pairs"][0]["antiresonance_hz"].get<double>() / (j["wave_speed_m_s"].get<double>() / 0.08), 1.0,
              1e-10);
  EXPECT_FALSE(j.contains("ieee176_k"));
  EXPECT_EQ(run("model bar --mode 44").code, 2);
  EXPECT_EQ(run("model bar --material nosuch").code, 2);
  EXPECT_EQ(run("model bar --length 0").code, 2);
  EXPECT_EQ(run("model bar --end-mass 0.001").code, 2);  // free-free has no end mass
}

// The seed's §5.1 (`model charge`, Figs 24–29). Noise-free with β = 0: the
// charge is a finite sum of exponentials, so the seed's largest-drop rule finds
// its numerical rank and Prony-SS reproduces the stepped-harmonic |Z| to
// rounding (0.1 dB is 1e9 times what it gets); and the harmonic truth's |Z|
// extrema are the modal solver's active short- and open-circuit frequencies
// (undamped: the extrema are the modes exactly; an independent solve).
TEST(CmdModel, ChargeSeed511) {
  const auto modal = run("model modal --json");
  ASSERT_EQ(modal.code, 0) << modal.out;
  const auto m = nlohmann::json::parse(modal.out);
  const std::string dir = std::string(PIEZO_BINARY_DIR) + "/test-model-charge";
  auto r = run("model charge --samples 1000 --plot-dir " + dir + " --csv " + dir + "-z.csv --json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["rayleigh_beta_s"].get<double>(), 0.0);
  auto has = [](const nlohmann::json& list, double f) {
    for (const auto& x : list)
      if (std::abs(x.get<double>() / f - 1.0) < 1e-6) return true;
    return false;
  };
  for (const auto& f : m["short_circuit_hz"]) EXPECT_TRUE(has(j["truth"]["resonances_hz"], f.get<double>())) << f;
  for (const auto& f : m["open_circuit_hz"]) EXPECT_TRUE(has(j["truth"]["antiresonances_hz"], f.get<double>())) << f;
  bool seen_seed = false, seen_fft = false;
  for (const auto& e : j["estimates"]) {
    if (e["method"] == "prony" && e["order_rule"] == "largest_drop") {
      seen_seed = true;
      EXPECT_LT(e["max_db"].get<double>(), 0.1);
      EXPECT_GT(e["scored_points"].get<int>(), 500);
      EXPECT_EQ(e["order"], j["singular_values"]["largest_drop_order"]);
    }
    // A 100 µs record resolves 10 kHz; the 3.1 kHz mode pair is not (the seed's "FFT worse").
    if (e["method"] == "fft" && e["samples"] == 1000) {
      seen_fft = true;
      EXPECT_GT(e["max_db"].get<double>(), 1.0);
    }
  }
  EXPECT_TRUE(seen_seed && seen_fft);
  EXPECT_FALSE(j["estimates"].dump().find("xspec") != std::string::npos) << "no cross spectra without noise";
  for (const char* f : {"charge-signals.svg", "charge-impedance.svg", "charge-singular-values.svg"}) {
    FILE* fp = std::fopen((dir + "/" + f).c_str(), "rb");
    ASSERT_NE(fp, nullptr) << f;
    std::fseek(fp, 0, SEEK_END);
    EXPECT_GT(std::ftell(fp), 1000) << f;
    std::fclose(fp);
  }
  FILE* csv = std::fopen((dir + "-z.csv").c_str(), "r");
  ASSERT_NE(csv, nullptr);
  int lines = 0;
  for (int c; (c = std::fgetc(csv)) != EOF;) lines += c == '\n';
  std::fclose(csv);
  EXPECT_EQ(lines, 601);  // header + 200 Hz … 120 kHz
}

// §5.1.2 (10 % noise on the charge, β = 1e-7 s): averaging 20 records cuts the
// noise part of the cross spectra's |Z| error by about √20 against one
// record's FFT ratio (the median over ~560 bins is a stable statistic: half is
// a wide margin); bad input is exit code 2.
TEST(CmdModel, ChargeSeed512) {
  auto r = run("model charge --noise 0.1 --samples 1000 --json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["rayleigh_beta_s"].get<double>(), 1e-7);
  double fft = -1, xspec = -1;
  for (const auto& e : j["estimates"]) {
    if (e["method"] == "fft" && e["samples"] == 50000) fft = e["median_db"].get<double>();
    if (e["method"] == "xspec") {
      xspec = e["median_db"].get<double>();
      EXPECT_EQ(e["records"].get<int>(), 20);
    }
  }
  ASSERT_GT(fft, 0);
  ASSERT_GT(xspec, 0);
  EXPECT_LT(xspec, 0.5 * fft);
  EXPECT_EQ(run("model charge --noise -1").code, 2);
  EXPECT_EQ(run("model charge --samples 50").code, 2);
  EXPECT_EQ(run("model charge --plot-format bmp").code, 2);
  EXPECT_EQ(run("model charge --material nosuch").code, 2);
}

// `model modal --plot-shapes` (seed Figs 7, 12, 13): the figure is written, and
// the JSON names it; a name that is not .png or .svg is bad input.
TEST(CmdModel, ModalPlotShapes) {
  const std::string file = std::string(PIEZO_BINARY_DIR) + "/test-model-shapes.svg";
  std::remove(file.c_str());
  auto r = run("model modal --plot-shapes " + file + " --json");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(nlohmann::json::parse(r.out)["shapes_plot"].get<std::string>(), file);
  FILE* fp = std::fopen(file.c_str(), "rb");
  ASSERT_NE(fp, nullptr);
  std::fseek(fp, 0, SEEK_END);
  EXPECT_GT(std::ftell(fp), 10000);
  std::fclose(fp);
  EXPECT_EQ(run("model modal --plot-shapes shapes.bmp").code, 2);
}
