// `--disturbance` on the command line (issue 33 item 4): `measure` on the
// embedded simulated bench writes the disturbances into /truth and into the
// samples, a malformed string and a real instrument are bad input (exit 2),
// and `demo` runs with them. The disturbances' own models are checked in
// tests/acquisition/test_sim_disturbances.cpp; `sim-instrument --disturbance`
// over TCP in test_cli_measure.cpp.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "acquisition/capture_file.hpp"
#include "tests/support/run_cli.hpp"
#include "tests/support/truth_attributes.hpp"

namespace fs = std::filesystem;
using namespace piezo;

namespace {
fs::path tmp_dir() {
  auto d = fs::temp_directory_path() / ("piezobench-disturbance-" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

// A /truth attribute: a number (NaN if absent) or a string ("" if absent).
using piezo::test::truth_number;  // tests/support/truth_attributes.hpp

std::string truth_string(const fs::path& file, const char* name) {
  hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  std::string v;
  if (f >= 0 && H5Aexists_by_name(f, "truth", name, H5P_DEFAULT) > 0) {
    hid_t a = H5Aopen_by_name(f, "truth", name, H5P_DEFAULT, H5P_DEFAULT);
    hid_t t = H5Aget_type(a);
    if (H5Tis_variable_str(t) > 0) {
      hid_t mt = H5Tget_native_type(t, H5T_DIR_ASCEND);
      char* p = nullptr;
      if (H5Aread(a, mt, &p) >= 0 && p) v = p;
      hid_t s = H5Aget_space(a);
      if (p) H5Dvlen_reclaim(mt, s, H5P_DEFAULT, &p);
      H5Sclose(s);
      H5Tclose(mt);
    } else {
      std::string buf(H5Tget_size(t), '\0');
      H5Aread(a, t, buf.data());
      v = buf.substr(0, buf.find('\0'));
    }
    H5Tclose(t);
    H5Aclose(a);
  }
  if (f >= 0) H5Fclose(f);
  return v;
}

double mean(const std::vector<double>& x, std::size_t n) {
  double s = 0;
  for (std::size_t k = 0; k < n; ++k) s += x[k];
  return s / static_cast<double>(n);
}
}  // namespace

// Offset and hum on the embedded bench: /truth records the settings and the
// offsets applied, and the pretrigger mean of a disturbed capture less that
// of the same capture undisturbed (same seed: the disturbances draw from their
// own generator, so the white noise is the same) is the recorded offset. The
// 1000 pretrigger samples span 0.1 ms at 10 MS/s, 1/200 of a 50 Hz period, so
// the hum is nearly constant over them and does not average out: its mean is
// checked against the hum phases /truth records, which the difference must then
// match within one ADC code (2/2^14 V at the ±1.25 V range: quantisation is the
// only thing not subtracted exactly).
TEST(CliDisturbance, MeasureRecordsTruthAndOffsetsThePretrigger) {
  const fs::path dir = tmp_dir();
  const std::string plan =
      "measure --instrument sim --shots 2 --samples 4000 --pretrigger 1000 --noise 0.01 --seed 5 "
      "--overwrite --json";
  auto r = test::run_cli(plan + " --disturbance offset=0.005,hum=0.005,mains=50 --out " +
                         (dir / "d.h5").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["shots_written"], 2);
  auto clean = test::run_cli(plan + " --out " + (dir / "c.h5").string());
  ASSERT_EQ(clean.exit_code, 0) << clean.err;

  const fs::path file = dir / "d.h5";
  EXPECT_EQ(truth_number(file, "disturbance_offset_v"), 0.005);
  EXPECT_EQ(truth_number(file, "disturbance_hum_v"), 0.005);
  EXPECT_EQ(truth_number(file, "disturbance_mains_hz"), 50.0);
  EXPECT_EQ(truth_string(file, "disturbances"), "offset=0.005,hum=0.005,mains=50");
  EXPECT_TRUE(std::isnan(
      truth_number(dir / "c.h5", "disturbance_offset_v")));  // undisturbed: none recorded

  const double off[2] = {truth_number(file, "disturbance_offset_v1"),
                         truth_number(file, "disturbance_offset_v2")};
  for (double o : off) {  // drawn in ±[0.5, 1]·offset
    EXPECT_GE(std::abs(o), 0.0025);
    EXPECT_LE(std::abs(o), 0.005);
  }
  // The hum's mean over the pretrigger, from the recorded phases.
  hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  std::vector<double> phase[2];
  const char* names[2] = {"disturbance_shot_hum_phase_v1_rad", "disturbance_shot_hum_phase_v2_rad"};
  for (int c = 0; c < 2; ++c) {
    hid_t a = H5Aopen_by_name(f, "truth", names[c], H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(a, 0) << names[c];
    phase[c].resize(2);
    H5Aread(a, H5T_NATIVE_DOUBLE, phase[c].data());
    H5Aclose(a);
  }
  H5Fclose(f);

  const auto d = acq::read_capture(file), u = acq::read_capture(dir / "c.h5");
  ASSERT_EQ(d.shots.size(), 2u);
  ASSERT_EQ(u.shots.size(), 2u);
  const std::size_t pre = 1000;
  const double fs_hz = d.shots[0].sample_rate_hz, code = 2.5 / 16384.0;
  for (std::size_t s = 0; s < 2; ++s) {
    const std::vector<double>* dv[2] = {&d.shots[s].v1, &d.shots[s].v2};
    const std::vector<double>* uv[2] = {&u.shots[s].v1, &u.shots[s].v2};
    for (int c = 0; c < 2; ++c) {
      double hum = 0;  // mean of the hum waveform over the pretrigger (t from the trigger)
      for (std::size_t k = 0; k < pre; ++k) {
        const double th = 2 * M_PI * 50.0 * (static_cast<double>(k) - pre) / fs_hz + phase[c][s];
        hum += 0.005 * (std::sin(th) + 0.30 * std::sin(2 * th) + 0.15 * std::sin(3 * th));
      }
      hum /= pre;
      const double diff = mean(*dv[c], pre) - mean(*uv[c], pre);
      std::printf("  shot %zu v%d: pretrigger mean shift %+.6f V, offset %+.6f V + hum %+.6f V\n",
                  s, c + 1, diff, off[c], hum);
      EXPECT_NEAR(diff, off[c] + hum, code) << "shot " << s << " v" << c + 1;
    }
  }
  fs::remove_all(dir);
}

TEST(CliDisturbance, MalformedStringIsBadInputNamingTheKey) {
  const fs::path out = tmp_dir() / "bad";  // measure's capture, or demo's folder
  for (const char* cmd :
       {"measure --instrument sim --samples 2000 --out ", "demo --shots 1 --out "}) {
    auto r = test::run_cli(std::string(cmd) + out.string() + " --disturbance hum=abc");
    EXPECT_EQ(r.exit_code, 2) << cmd << r.err;
    EXPECT_NE(r.err.find("hum"), std::string::npos) << cmd << r.err;
    r = test::run_cli(std::string(cmd) + out.string() + " --disturbance wobble=1");
    EXPECT_EQ(r.exit_code, 2) << cmd << r.err;
    EXPECT_NE(r.err.find("wobble"), std::string::npos) << cmd << r.err;
  }
  EXPECT_FALSE(fs::exists(out));
  fs::remove_all(tmp_dir());
}

// A real instrument has its own disturbances: the option is refused before
// anything connects (nothing listens on port 9 of localhost anyway).
TEST(CliDisturbance, RealInstrumentIsRefused) {
  auto r =
      test::run_cli("measure --instrument tcp://127.0.0.1:9 --disturbance offset=0.005 --out " +
                    (tmp_dir() / "real.h5").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--disturbance applies to the simulated bench only"), std::string::npos)
      << r.err;
  fs::remove_all(tmp_dir());
}

// The demo's simulated bench takes the disturbances (the main capture's /truth
// has them) and the pipeline runs to the end, the gap diagnosis included (its
// verdict is not checked: the estimators do not model the baseline yet).
TEST(CliDisturbance, DemoRuns) {
  const fs::path dir = tmp_dir() / "demo";
  auto r = test::run_cli(
      "demo --json --shots 1 --noise 0.02 "
      "--disturbance offset=0.005,hum=0.005,mains=50,pink=1 --out " +
      dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j.contains("diagnosis") && j["diagnosis"].contains("verdict_text"))
      << r.out.substr(0, 2000);
  const fs::path cap = j["capture"].get<std::string>();
  EXPECT_EQ(truth_string(cap, "disturbances"), "offset=0.005,hum=0.005,mains=50,pink=1");
  EXPECT_DOUBLE_EQ(truth_number(cap, "disturbance_pink_rel"), 0.01);
  fs::remove_all(dir);
}
