// The measurement runner on the simulated bench: in-process and over TCP
// (same SCPI drivers, same simulated instruments), and the fault cases.
// Physics is a test double (an ideal capacitor behind R1, exact), so the
// recorded v2 can be checked against the closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "acquisition/capture_file.hpp"
#include "acquisition/runner.hpp"
#include "drivers/sim/sim_awg.hpp"
#include "drivers/sim/sim_daq.hpp"
#include "drivers/sim/tcp_server.hpp"
#include "drivers/scpi_client.hpp"
#include "tests/support/rc_physics.hpp"

namespace fs = std::filesystem;
using namespace piezo;
using drivers::sim::FaultPlan;

namespace {
constexpr double kR1 = 3140.0, kC = 2.1e-9;

fs::path tmp_dir() {
  auto d = fs::temp_directory_path() /
           ("piezobench-runner-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::shared_ptr<drivers::sim::SimBench> sim_bench(std::uint64_t seed, FaultPlan faults = {},
                                                   double noise = 0.0) {
  drivers::sim::DaqImperfections imp;
  imp.noise_rel[0] = imp.noise_rel[1] = noise;
  return std::make_shared<drivers::sim::SimBench>(std::make_unique<test::RcPhysics>(kR1, kC), imp, seed,
                                                  faults);
}

acq::MeasurementPlan seed_plan(int shots) {
  acq::MeasurementPlan p;  // the seed's lab drive: 1 V, 3000 1/s, 10 MS/s
  p.samples = 4000;
  p.pretrigger_samples = 100;
  p.shots = shots;
  p.setup.divider_r1_ohm = kR1;
  return p;
}
}  // namespace

TEST(Runner, InProcessCaptureMatchesTheClosedForm) {
  auto dir = tmp_dir();
  auto bench = acq::open_bench({"sim", std::nullopt}, sim_bench(7));
  std::vector<acq::Progress> seen;
  auto res = acq::run_measurement(bench, seed_plan(2), dir / "c.h5", {},
                                  [&](const acq::Progress& p) { seen.push_back(p); });
  EXPECT_EQ(res.shots_written, 2);
  EXPECT_FALSE(seen.empty());
  auto cap = acq::read_capture(dir / "c.h5");
  ASSERT_EQ(cap.shots.size(), 2u);
  const auto& s = cap.shots[0];
  EXPECT_EQ(s.pretrigger_samples, 100);
  EXPECT_EQ(s.decay_per_s, 3000.0);
  ASSERT_TRUE(s.daq_range_v);
  // 14-bit ADC over ±1.25 V: one LSB = 1.53e-4 V; quantisation error <= LSB/2,
  // plus the first-order-hold vs exact-exponential difference (< 1e-6 V here).
  // The AWG ramps from its idle level at t = −Δt to the first sample at t = 0
  // (drivers/sim/sim_bench.cpp), so v2(0) is the RC response to that ramp.
  const double lsb = *s.daq_range_v / 8192.0;
  const double tau = kR1 * kC, dt = 1e-7;
  const double v2_0 = (dt - tau * (1 - std::exp(-dt / tau))) / dt;
  for (std::size_t i = 0; i < s.samples(); ++i) {
    double t = (static_cast<double>(i) - 100.0) / 1e7;
    double v1 = t >= 0 ? std::exp(-3000.0 * t) : 0.0;
    double v2 = t >= 0 ? (std::exp(-3000.0 * t) - std::exp(-t / tau)) / (1 - 3000.0 * tau) + v2_0 * std::exp(-t / tau)
                       : 0.0;
    ASSERT_NEAR(s.v1[i], v1, 0.5 * lsb + 1e-6) << i;
    ASSERT_NEAR(s.v2[i], v2, 0.5 * lsb + 1e-5) << i;
  }
}

TEST(Runner, TcpEqualsInProcessSampleForSample) {
  auto dir = tmp_dir();
  auto tcp_bench = sim_bench(42, {}, 0.03);
  drivers::sim::TcpServer awg_srv(std::make_shared<drivers::sim::SimAwg>(tcp_bench), "127.0.0.1", 0);
  drivers::sim::TcpServer daq_srv(std::make_shared<drivers::sim::SimDaq>(tcp_bench), "127.0.0.1", 0);
  awg_srv.start();
  daq_srv.start();
  acq::BenchAddress addr{"tcp://127.0.0.1:" + std::to_string(awg_srv.port()),
                         "tcp://127.0.0.1:" + std::to_string(daq_srv.port())};
  auto remote = acq::open_bench(addr);
  EXPECT_NE(remote.description.find("33522B"), std::string::npos);
  acq::run_measurement(remote, seed_plan(3), dir / "tcp.h5");
  auto local = acq::open_bench({"sim", std::nullopt}, sim_bench(42, {}, 0.03));
  acq::run_measurement(local, seed_plan(3), dir / "local.h5");
  auto a = acq::read_capture(dir / "tcp.h5");
  auto b = acq::read_capture(dir / "local.h5");
  ASSERT_EQ(a.shots.size(), 3u);
  ASSERT_EQ(b.shots.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(a.shots[k].v1, b.shots[k].v1) << k;
    EXPECT_EQ(a.shots[k].v2, b.shots[k].v2) << k;
  }
  EXPECT_NE(a.shots[0].v2, a.shots[1].v2);  // noise differs between shots
}

struct FaultCase {
  const char* name;
  FaultPlan::Kind kind;
  const char* message;  // substring of the error
};

class RunnerFaults : public ::testing::TestWithParam<FaultCase> {};

TEST_P(RunnerFaults, ClearMessageAndEarlierShotsReadable) {
  const auto& c = GetParam();
  auto dir = tmp_dir();
  auto bench = acq::open_bench({"sim", std::nullopt}, sim_bench(3, FaultPlan{c.kind, 2}));
  try {
    acq::run_measurement(bench, seed_plan(4), dir / "f.h5");
    FAIL() << c.name << ": the run did not report the fault";
  } catch (const acq::RunError& e) {
    std::string msg = e.what();
    EXPECT_NE(msg.find("shot 3 of 4"), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.message), std::string::npos) << msg;
    EXPECT_EQ(e.partial().shots_written, 2);
  }
  auto cap = acq::read_capture(dir / "f.h5");
  EXPECT_EQ(cap.shots.size(), 2u);
}

INSTANTIATE_TEST_SUITE_P(
    All, RunnerFaults,
    ::testing::Values(FaultCase{"close_mid_fetch", FaultPlan::Kind::CloseMidFetch, "closed the connection"},
                      FaultCase{"reply_timeout", FaultPlan::Kind::NoReplyToFetch, "no reply"},
                      FaultCase{"malformed_block", FaultPlan::Kind::MalformedBlock, "malformed binary block"},
                      FaultCase{"truncated_block", FaultPlan::Kind::TruncatedBlock, "closed the connection"},
                      FaultCase{"instrument_error", FaultPlan::Kind::ErrorOnConfigure, "-222"}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(Runner, ClippedShotIsStoredFlaggedAndStopsTheRun) {
  auto dir = tmp_dir();
  auto bench = acq::open_bench({"sim", std::nullopt}, sim_bench(5));
  auto plan = seed_plan(3);
  plan.range_v = 0.5;  // v1 peaks at 1 V
  try {
    acq::run_measurement(bench, plan, dir / "clip.h5");
    FAIL() << "clipping not reported";
  } catch (const acq::RunError& e) {
    EXPECT_NE(std::string(e.what()).find("clipped"), std::string::npos);
    EXPECT_EQ(e.partial().shots_written, 1);
  }
  auto cap = acq::read_capture(dir / "clip.h5");
  ASSERT_EQ(cap.shots.size(), 1u);
  EXPECT_EQ(cap.shots[0].daq_range_v, 0.5);
}

TEST(Runner, CancellationKeepsWhatWasAcquired) {
  auto dir = tmp_dir();
  auto bench = acq::open_bench({"sim", std::nullopt}, sim_bench(5));
  std::atomic<bool> cancel{false};
  auto res = acq::run_measurement(bench, seed_plan(5), dir / "x.h5", {},
                                  [&](const acq::Progress& p) {
                                    if (p.shot == 2) cancel = true;
                                  },
                                  &cancel);
  EXPECT_TRUE(res.cancelled);
  EXPECT_EQ(res.shots_written, 3);  // the shot in progress completes
  EXPECT_EQ(acq::read_capture(dir / "x.h5").shots.size(), 3u);
}

TEST(Runner, TruthIsRecordedForSimulatedBenches) {
  auto dir = tmp_dir();
  auto bench = acq::open_bench({"sim", std::nullopt}, sim_bench(5));
  acq::run_measurement(bench, seed_plan(1), dir / "t.h5");
  // The reader ignores /truth; its presence is checked through capture info's raw view elsewhere.
  EXPECT_EQ(acq::read_capture(dir / "t.h5").shots.size(), 1u);
}
