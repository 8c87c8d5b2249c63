// The measurement runner with the Comedi DAQ driver on the embedded
// simulated bench (the simulated PCI-6110, drivers/sim/sim_comedi_board.*):
// the two AWG pairings with a Comedi board (Keysight 33500 + Comedi,
// Tektronix AWG5000 + Comedi) record what the Keysight + Infiniium bench
// records, sample for sample, for the same seed; and the board's faults
// (overrun, no data, device gone) stop the run with a message naming the
// shot and the device, the earlier shots kept in the capture.
#include <gtest/gtest.h>

#include <filesystem>

#include "acquisition/capture_file.hpp"
#include "acquisition/plan.hpp"
#include "acquisition/runner.hpp"
#include "tests/support/rc_physics.hpp"

namespace fs = std::filesystem;
using namespace piezo;
using drivers::sim::FaultPlan;

namespace {
constexpr double kR1 = 3140.0, kC = 2.1e-9;

fs::path tmp_dir() {
  auto d =
      fs::temp_directory_path() / ("piezobench-runner-comedi-" + std::to_string(::getpid()) + "-" +
                                   ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// 12 bits: the 6110E's converter (the Infiniium twin quantises the same way).
std::shared_ptr<drivers::sim::SimBench> bench12(std::uint64_t seed, FaultPlan faults = {}) {
  drivers::sim::DaqImperfections imp;
  imp.noise_rel[0] = imp.noise_rel[1] = 0.03;
  imp.adc_bits = 12;
  return std::make_shared<drivers::sim::SimBench>(std::make_unique<test::RcPhysics>(kR1, kC), imp,
                                                  seed, faults);
}

// A plan the 6110E follows exactly: no pretrigger (a Comedi command starts
// at its trigger), 5 MS/s (the board's top rate, 200 ns on its timebase),
// ±2 V (one of its ranges).
acq::MeasurementPlan comedi_plan(int shots) {
  acq::MeasurementPlan p;
  p.samples = 4000;
  p.pretrigger_samples = 0;
  p.sample_rate_hz = 5e6;
  p.range_v = 2.0;
  p.shots = shots;
  p.setup.divider_r1_ohm = kR1;
  return p;
}
}  // namespace

void expect_equal_shots(const acq::Capture& cap, const acq::Capture& ref, const std::string& what) {
  ASSERT_EQ(cap.shots.size(), ref.shots.size()) << what;
  for (std::size_t k = 0; k < ref.shots.size(); ++k) {
    EXPECT_EQ(cap.shots[k].sample_rate_hz, ref.shots[k].sample_rate_hz) << what << " shot " << k;
    EXPECT_EQ(cap.shots[k].daq_range_v, ref.shots[k].daq_range_v) << what << " shot " << k;
    EXPECT_EQ(cap.shots[k].v1, ref.shots[k].v1) << what << " shot " << k;
    EXPECT_EQ(cap.shots[k].v2, ref.shots[k].v2) << what << " shot " << k;
  }
  ASSERT_GE(cap.shots.size(), 2u) << what;
  EXPECT_NE(cap.shots[0].v2, cap.shots[1].v2) << what;  // seeded noise differs
}

// Keysight 33500 + Comedi board against `measure --instrument sim` (Keysight + Infiniium).
TEST(ComediRunner, KeysightWithComediEqualsTheEmbeddedBenchSampleForSample) {
  auto dir = tmp_dir();
  auto local = acq::open_bench({"sim", std::nullopt}, bench12(42));
  acq::run_measurement(local, comedi_plan(3), dir / "local.h5");
  auto bench =
      acq::open_bench({"sim", "comedi-sim:///dev/comedi0?trigger=pfi0&softcal=1"}, bench12(42));
  EXPECT_NE(bench.description.find("COMEDI,pci-6110,/dev/comedi0,ni_pcimio"), std::string::npos)
      << bench.description;
  acq::run_measurement(bench, comedi_plan(3), dir / "comedi.h5");
  expect_equal_shots(acq::read_capture(dir / "comedi.h5"), acq::read_capture(dir / "local.h5"),
                     "keysight+comedi");
}

// Tektronix AWG5000 + Comedi board. The AWG5014C plays at 10 MS/s or faster
// and the 6110E samples at 5 MS/s or slower, and the runner gives both the
// plan's one rate: at 10 MS/s the board's command_test rounds the scan
// period to 200 ns (the shot states 5 MS/s). No runner plan makes the
// Infiniium do the same, so the reference is the embedded bench's Keysight +
// Infiniium drivers driven as the runner drives them, the generator at 10
// MS/s and the Infiniium at 5 MS/s, on an identical bench.
TEST(ComediRunner, TektronixWithComediEqualsTheEmbeddedBenchSampleForSample) {
  auto dir = tmp_dir();
  auto plan = comedi_plan(3);
  plan.sample_rate_hz = 1e7;
  auto bench =
      acq::open_bench({"sim?awg=tektronix", "comedi-sim:///dev/comedi0?softcal=1"}, bench12(42));
  EXPECT_NE(bench.description.find("TEKTRONIX,AWG5014C"), std::string::npos) << bench.description;
  acq::run_measurement(bench, plan, dir / "tek.h5");
  const auto cap = acq::read_capture(dir / "tek.h5");
  ASSERT_EQ(cap.shots.size(), 3u);
  EXPECT_EQ(cap.shots[0].sample_rate_hz, 5e6);

  auto local = acq::open_bench({"sim", std::nullopt}, bench12(42));
  drivers::ArbWaveform w;
  w.samples =
      acq::synthesize(plan.excitation, plan.sample_rate_hz, plan.samples - plan.pretrigger_samples);
  w.sample_rate_hz = plan.sample_rate_hz;
  w.peak_v = plan.excitation.amplitude_v;
  local.awg->load(w);
  drivers::DaqConfig dc;
  dc.sample_rate_hz = 5e6;
  dc.record_length = plan.samples;
  dc.pretrigger_samples = 0;
  dc.range_v[0] = dc.range_v[1] = plan.daq_range_v();
  for (std::size_t k = 0; k < cap.shots.size(); ++k) {
    local.daq->configure(dc);
    local.daq->arm();
    local.awg->output(true);
    local.awg->trigger();
    const auto r = local.daq->fetch(2.0);
    EXPECT_EQ(cap.shots[k].v1, r.v1) << "shot " << k;
    EXPECT_EQ(cap.shots[k].v2, r.v2) << "shot " << k;
  }
  EXPECT_NE(cap.shots[0].v2, cap.shots[1].v2);
}

TEST(ComediRunner, TheSimulatedBoardNeedsTheEmbeddedBench) {
  try {
    acq::open_bench({"tcp://127.0.0.1:1", "comedi-sim:///dev/comedi0"});
    FAIL() << "accepted";
  } catch (const std::exception& e) {
    // The AWG's connection fails first or the board is refused: either names the problem.
    const std::string m = e.what();
    EXPECT_TRUE(m.find("127.0.0.1:1") != std::string::npos ||
                m.find("embedded simulated bench") != std::string::npos)
        << m;
  }
  EXPECT_THROW(acq::open_bench({"sim", "tcp://127.0.0.1:5026"}, bench12(1)), std::invalid_argument);
  EXPECT_THROW(
      acq::open_bench({"sim", "comedi-sim:///dev/comedi0"},
                      [] {
                        drivers::sim::DaqImperfections imp;  // 14 bits: not the 6110E's converter
                        return std::make_shared<drivers::sim::SimBench>(
                            std::make_unique<test::RcPhysics>(kR1, kC), imp, 1);
                      }()),
      std::invalid_argument);
}

struct ComediFaultCase {
  const char* name;
  FaultPlan::Kind kind;
  const char* message;
};

class ComediRunnerFaults : public ::testing::TestWithParam<ComediFaultCase> {};

TEST_P(ComediRunnerFaults, ClearMessageNamingTheShotEarlierShotsKept) {
  const auto& c = GetParam();
  auto dir = tmp_dir();
  auto bench =
      acq::open_bench({"sim", "comedi-sim:///dev/comedi0"}, bench12(3, FaultPlan{c.kind, 2}));
  acq::RunnerOptions ro;
  ro.fetch_timeout_s = 0.2;
  try {
    acq::run_measurement(bench, comedi_plan(4), dir / "f.h5", ro);
    FAIL() << c.name << ": the run did not report the fault";
  } catch (const acq::RunError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("shot 3 of 4"), std::string::npos) << msg;
    EXPECT_NE(msg.find("comedi-sim:///dev/comedi0 (pci-6110)"), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.message), std::string::npos) << msg;
    EXPECT_NE(msg.find("2 earlier shot(s) are safe in"), std::string::npos) << msg;
    EXPECT_EQ(e.partial().shots_written, 2);
  }
  auto cap = acq::read_capture(dir / "f.h5");
  ASSERT_EQ(cap.shots.size(), 2u);
  EXPECT_EQ(cap.shots[1].v1.size(), 4000u);
}

INSTANTIATE_TEST_SUITE_P(
    All, ComediRunnerFaults,
    ::testing::Values(ComediFaultCase{"overrun", FaultPlan::Kind::ComediOverrun,
                                      "buffer overrun after 1333 of 4000 scans"},
                      ComediFaultCase{"no_data", FaultPlan::Kind::ComediNoData,
                                      "no samples for 0.2 s"},
                      ComediFaultCase{"device_gone", FaultPlan::Kind::ComediDeviceGone,
                                      "device gone after 1333 of 4000 scans"}),
    [](const auto& info) { return std::string(info.param.name); });
