// A capture written by another tool (h5py, fixtures/make_fixtures.py:
// h5py-bvd-exp-decay.h5 — float32 in gzip-compressed chunks, int32 and
// fixed-length string attributes, a /truth group) replays to the same numbers
// as the same data written by the bench's CaptureWriter.
//
// "The same data": the samples are recomputed here from the closed form the
// script uses (tests/dsp/bvd_model.cpp, the same BVD circuit) and rounded to
// float32 as the script stores them; they must equal the fixture's samples bit
// for bit before the two files are compared, so any difference in the replay
// comes from the file, not from the data.
#include <gtest/gtest.h>

#include "acquisition/capture_file.hpp"
#include "tests/dsp/bvd_model.hpp"
#include "tests/replay/replay_test_support.hpp"

using namespace piezo;
namespace fs = std::filesystem;

namespace {
const fs::path kFixture = fs::path(PIEZO_SOURCE_DIR) / "fixtures" / "h5py-bvd-exp-decay.h5";
constexpr double kR1 = 3140.0, kFs = 1e7;
constexpr std::size_t kN = 8000, kPre = 200;

// The bench's view of the same measurement, written by CaptureWriter.
acq::Capture bench_capture() {
  const auto resp = bvd::divider_response(bvd::tube_bvd_rayleigh(1e-7), kR1, 1.0, 3000.0);
  acq::Capture cap;
  cap.setup.divider_r1_ohm = kR1;
  cap.setup.transducer_id = "fixture-bvd";
  cap.setup.material = "apc850";
  acq::Shot s;
  s.sample_rate_hz = kFs;
  s.excitation = acq::Excitation::ExpDecay;
  s.amplitude_v = 1.0;
  s.decay_per_s = 3000.0;
  s.pretrigger_samples = kPre;
  s.store_float32 = true;
  for (auto [x, v] : {std::pair(&resp.v1, &s.v1), std::pair(&resp.v2, &s.v2)})
    for (double y : bvd::sample(*x, kFs, kN, kPre)) v->push_back(static_cast<float>(y));
  cap.shots.push_back(std::move(s));
  return cap;
}

// The result without what names the file (the capture path, the acquire note).
nlohmann::json numbers(nlohmann::json j) {
  j.erase("path");
  j.erase("sha256");
  j["result"].erase("capture");
  if (j["result"].contains("diagnosis") && j["result"]["diagnosis"].is_object()) j["result"]["diagnosis"].erase("seconds");
  if (j["result"].contains("work"))  // the work counts stay, the phases' wall times go
    for (auto& p : j["result"]["work"]["phases"]) p.erase("seconds");
  return j;
}
}  // namespace

TEST(ReplayFixture, H5pyCaptureReplaysLikeTheSameDataWrittenByTheBench) {
  const auto dir = test::fresh_dir("replay-fixture");
  const auto bench = dir / "bench-bvd.h5";
  const auto cap = bench_capture();
  acq::write_capture(bench, cap);

  const auto h5py = acq::read_capture(kFixture);
  ASSERT_EQ(h5py.shots.size(), 1u);
  ASSERT_EQ(h5py.shots[0].samples(), kN);
  ASSERT_EQ(h5py.shots[0].pretrigger_samples, static_cast<std::int64_t>(kPre));
  std::size_t differ = 0;
  for (std::size_t i = 0; i < kN; ++i)
    differ +=
        h5py.shots[0].v1[i] != cap.shots[0].v1[i] || h5py.shots[0].v2[i] != cap.shots[0].v2[i];
  ASSERT_EQ(differ, 0u) << "the fixture no longer holds the closed form of tests/dsp/bvd_model.cpp "
                           "(regenerate with `make fixtures`)";

  const auto out = dir / "results.h5";
  auto r = test::run_cli("replay '" + kFixture.string() + "' '" + bench.string() + "' --out '" +
                         out.string() + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto content = test::read_content(out);
  ASSERT_EQ(content.size(), 2u);
  const auto& a = content.begin()->second;
  const auto& b = std::next(content.begin())->second;
  ASSERT_EQ(a.status, "ok");
  ASSERT_EQ(b.status, "ok");
  EXPECT_NE(a.sha256, b.sha256);  // two different files…
  EXPECT_EQ(numbers(a.json), numbers(b.json)) << a.json.dump(1) << "\n"
                                              << b.json.dump(1);  // …the same numbers
  ASSERT_EQ(a.curves.size(), b.curves.size());
  for (std::size_t c = 0; c < a.curves.size(); ++c) {
    EXPECT_EQ(a.curves[c].f_hz, b.curves[c].f_hz);
    EXPECT_EQ(a.curves[c].z_ohm, b.curves[c].z_ohm) << a.curves[c].label;
  }
  // The numbers are the real thing: the update ran, the BVD's three resonances were found.
  const auto& res = a.json["result"];
  ASSERT_GE(res["resonances_hz"].size(), 3u) << res.dump(1);
  EXPECT_NEAR(res["resonances_hz"][0].get<double>(), 50.3e3, 0.5e3);
  EXPECT_EQ(res["parameters"].size(), 4u) << res.dump(1);
  fs::remove_all(dir);
}
