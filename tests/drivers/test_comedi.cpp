// The Comedi DAQ driver through its seam (drivers/comedi/board.hpp): the
// address grammar, the driver against the simulated PCI-6110
// (drivers/sim/sim_comedi_board.*) — range choice, timer rounding, the
// board's refusals, a shot equal sample for sample to the Keysight 33500 +
// Infiniium path on an identical bench, comedilib's conversion formulas, and
// the faults (overrun, no data, device gone) as messages naming the device —
// and, where the kernel's comedi_test driver is configured as /dev/comedi0,
// the real comedilib seam against it (skipped, with the reason, elsewhere).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>

#include "drivers/comedi/address.hpp"
#include "drivers/comedi/driver.hpp"
#include "drivers/infiniium/driver.hpp"
#include "drivers/keysight33500/driver.hpp"
#include "drivers/scpi_client.hpp"
#include "drivers/sim/loopback_transport.hpp"
#include "drivers/sim/sim_awg.hpp"
#include "drivers/sim/sim_comedi_board.hpp"
#include "drivers/sim/sim_daq.hpp"
#include "tests/support/rc_physics.hpp"
#include "tests/support/scpi_link.hpp"

using namespace piezo;
using namespace piezo::drivers;
using sim::FaultPlan;

namespace {

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

constexpr double kR1 = 3140.0, kC = 2.1e-9;

std::shared_ptr<sim::SimBench> bench12(std::uint64_t seed, double noise, FaultPlan f = {}) {
  sim::DaqImperfections imp;
  imp.noise_rel[0] = imp.noise_rel[1] = noise;
  imp.adc_bits = 12;  // the 6110E's converter
  return std::make_shared<sim::SimBench>(std::make_unique<test::RcPhysics>(kR1, kC), imp, seed, f);
}

// The AWG (Keysight twin over the loopback) of a bench, loaded and on.
std::unique_ptr<keysight33500::Driver> awg_on(const std::shared_ptr<sim::SimBench>& b,
                                              const ArbWaveform& w) {
  auto awg = std::make_unique<keysight33500::Driver>(
      std::make_unique<sim::LoopbackTransport>(std::make_shared<sim::SimAwg>(b), "sim://awg"));
  awg->load(w);
  awg->output(true);
  return awg;
}

std::unique_ptr<comedi::Driver> comedi_on(const std::shared_ptr<sim::SimBench>& b,
                                          const std::string& address, bool softcal = false,
                                          sim::SimComediBoard** board = nullptr) {
  const auto a = comedi::parse_address(address);
  auto fake = std::make_unique<sim::SimComediBoard>(b, a.device, softcal);
  if (board) *board = fake.get();
  return std::make_unique<comedi::Driver>(std::move(fake), a);
}

DaqConfig plan(double rate, std::size_t n, double range) {
  DaqConfig c;
  c.sample_rate_hz = rate;
  c.record_length = n;
  c.pretrigger_samples = 0;
  c.range_v[0] = c.range_v[1] = range;
  return c;
}

// ------------------------------------------------------------ address
TEST(ComediAddress, DefaultsAndOptions) {
  EXPECT_TRUE(comedi::parse_address("comedi-sim:///dev/comedi0?softcal=1").sim_softcal);
  EXPECT_THROW(comedi::parse_address("comedi:///dev/comedi0?softcal=1"), std::invalid_argument);
  auto a = comedi::parse_address("comedi:///dev/comedi0");
  EXPECT_FALSE(a.simulated);
  EXPECT_EQ(a.device, "/dev/comedi0");
  EXPECT_TRUE(a.external_trigger);
  EXPECT_EQ(a.pfi, 0u);
  EXPECT_EQ(a.aref, comedi::Aref::Diff);
  EXPECT_EQ(a.channels[0], 0u);
  EXPECT_EQ(a.channels[1], 1u);
  EXPECT_EQ(a.to_string(), "comedi:///dev/comedi0?trigger=pfi0&aref=diff&channels=0,1");

  a = comedi::parse_address(
      "comedi-sim:///dev/comedi2?trigger=pfi7&edge=falling&aref=rse&channels=3,1");
  EXPECT_TRUE(a.simulated);
  EXPECT_EQ(a.device, "/dev/comedi2");
  EXPECT_EQ(a.pfi, 7u);
  EXPECT_TRUE(a.falling);
  EXPECT_EQ(a.aref, comedi::Aref::Ground);
  EXPECT_EQ(a.channels[0], 3u);
  EXPECT_EQ(a.channels[1], 1u);
  EXPECT_EQ(comedi::parse_address(a.to_string()).to_string(), a.to_string());

  a = comedi::parse_address("comedi:///dev/comedi0?trigger=software&aref=nrse");
  EXPECT_FALSE(a.external_trigger);
  EXPECT_EQ(a.aref, comedi::Aref::Common);
  EXPECT_TRUE(comedi::is_comedi_address("comedi-sim:///dev/comedi0"));
  EXPECT_FALSE(comedi::is_comedi_address("tcp://h:1"));
}

TEST(ComediAddress, MistakesAreNamed) {
  struct Case {
    const char* text;
    const char* why;
  };
  for (const Case& c :
       {Case{"comedi://dev/comedi0", "/dev/comediN"}, Case{"comedi:///dev/comedi", "/dev/comediN"},
        Case{"comedi:///dev/comediX", "device number"},
        Case{"comedi:///dev/comedi0?trigger=pfi", "PFI line"},
        Case{"comedi:///dev/comedi0?trigger=ext", "pfiN or software"},
        Case{"comedi:///dev/comedi0?aref=single", "diff, rse or nrse"},
        Case{"comedi:///dev/comedi0?channels=1", "C1,C2"},
        Case{"comedi:///dev/comedi0?channels=2,2", "two different"},
        Case{"comedi:///dev/comedi0?speed=1", "unknown option 'speed'"},
        Case{"comedi:///dev/comedi0?trigger", "needs a value"},
        Case{"daq://x", "expected comedi"}}) {
    try {
      comedi::parse_address(c.text);
      ADD_FAILURE() << c.text << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_TRUE(contains(e.what(), c.why)) << c.text << ": " << e.what();
      EXPECT_TRUE(contains(e.what(), c.text)) << e.what();
    }
  }
}

// ------------------------------------------------------------ driver on the simulated board
TEST(ComediDriver, IdentityRangesAndTimerRounding) {
  auto b = bench12(1, 0.0);
  sim::SimComediBoard* board = nullptr;
  auto daq = comedi_on(b, "comedi-sim:///dev/comedi0", false, &board);
  EXPECT_EQ(daq->identity(), "COMEDI,pci-6110,/dev/comedi0,ni_pcimio");
  // ±1.25 V fits the ±2 V range (the smallest of the table that holds it);
  // 10 MS/s is beyond the 6110E: command_test moves the period to 200 ns.
  daq->configure(plan(1e7, 500, 1.25));
  EXPECT_EQ(daq->scan_period_ns(), 200u);
  EXPECT_EQ(daq->conversion(0), "comedi_to_phys over [-2, 2] V");
  // 3 MS/s = 333.3 ns: rounded to the 20 MHz timebase's 350 ns.
  daq->configure(plan(3e6, 500, 0.2));
  EXPECT_EQ(daq->scan_period_ns(), 350u);
  EXPECT_EQ(daq->conversion(1), "comedi_to_phys over [-0.2, 0.2] V");
  auto awg = awg_on(b, test::seeded_waveform(5, 400, 1e6, 0.15));
  daq->arm();
  awg->trigger();
  auto r = daq->fetch(1.0);
  EXPECT_NEAR(r.sample_rate_hz, 1e9 / 350.0, 1e-6);
  EXPECT_EQ(r.range_v[0], 0.2);
  EXPECT_EQ(r.pretrigger_samples, 0u);
  EXPECT_EQ(r.v1.size(), 500u);
  EXPECT_EQ(board->commands(), 1);
  EXPECT_EQ(board->cancels(),
            1);  // the finished command released (the kernel keeps it busy until then)
}

TEST(ComediDriver, WhatTheBoardCannotDoIsRefusedWithTheReason) {
  auto b = bench12(1, 0.0);
  auto daq = comedi_on(b, "comedi-sim:///dev/comedi0");
  auto expect_refusal = [&](const DaqConfig& c, const std::string& part, bool instrument_error) {
    try {
      daq->configure(c);
      ADD_FAILURE() << part << ": accepted";
    } catch (const InstrumentError& e) {
      EXPECT_TRUE(instrument_error) << e.what();
      EXPECT_TRUE(contains(e.what(), part)) << e.what();
      EXPECT_TRUE(contains(e.what(), "comedi-sim:///dev/comedi0 (pci-6110)")) << e.what();
    } catch (const std::invalid_argument& e) {
      EXPECT_FALSE(instrument_error) << e.what();
      EXPECT_TRUE(contains(e.what(), part)) << e.what();
    }
  };
  auto c = plan(1e6, 100, 1.0);
  c.pretrigger_samples = 10;
  expect_refusal(c, "no samples before it", false);
  expect_refusal(plan(1e6, 100, 60.0),
                 "no range holds ±60 V (the board offers [-50, 50], [-20, 20]", false);
  c = plan(1e6, 100, 1.0);
  c.coupling = Coupling::Ac;
  expect_refusal(c, "DC only", false);
  c.coupling = Coupling::Dc1M;
  c.external_trigger = false;
  expect_refusal(c, "the address names a PFI trigger", false);
  // The 6110's inputs are differential only: the channel list is refused (stage 5).
  auto rse = comedi_on(b, "comedi-sim:///dev/comedi0?aref=rse");
  try {
    rse->configure(plan(1e6, 100, 1.0));
    ADD_FAILURE() << "rse accepted";
  } catch (const InstrumentError& e) {
    EXPECT_TRUE(contains(e.what(), "the channel list is not possible")) << e.what();
  }
  // Software start: the simulated board does not model it (stage 1).
  auto sw = comedi_on(b, "comedi-sim:///dev/comedi0?trigger=software");
  c.external_trigger = false;
  try {
    sw->configure(c);
    ADD_FAILURE() << "software start accepted by the simulated board";
  } catch (const InstrumentError& e) {
    EXPECT_TRUE(contains(e.what(), "software start")) << e.what();
    EXPECT_TRUE(contains(e.what(), "a trigger source is not supported")) << e.what();
  }
  EXPECT_THROW(comedi_on(b, "comedi-sim:///dev/comedi0?channels=0,4"), InstrumentError);
  EXPECT_THROW(comedi_on(bench12(1, 0.0), "comedi-sim:///dev/comedi0?trigger=pfi12")
                   ->configure(plan(1e6, 10, 1)),
               InstrumentError);
}

// The Infiniium path on one bench, the Comedi path on an identical one
// (same seed, 12-bit quantisation, same drive): with the soft calibration's
// ideal polynomial the volts are the Infiniium's exactly; without it (an
// E-series board) comedi_to_phys maps the same raw codes, which the test
// recovers from the Infiniium's volts.
void expect_same_shots_as_infiniium(bool softcal) {
  const double range = 2.0, rate = 5e6;
  const std::size_t n = 3000;
  const auto w = test::seeded_waveform(11, 2500, rate, 1.5);
  auto ref_bench = bench12(29, 0.02), com_bench = bench12(29, 0.02);
  auto ref_awg = awg_on(ref_bench, w);
  auto com_awg = awg_on(com_bench, w);
  infiniium::Driver ref_daq(std::make_unique<sim::LoopbackTransport>(
      std::make_shared<sim::SimDaq>(ref_bench), "sim://daq"));
  auto com_daq = comedi_on(com_bench, "comedi-sim:///dev/comedi0?trigger=pfi0", softcal);
  for (int shot = 0; shot < 2; ++shot) {
    ref_daq.configure(plan(rate, n, range));
    com_daq->configure(plan(rate, n, range));
    EXPECT_EQ(com_daq->conversion(0),
              softcal ? "softcal polynomial" : "comedi_to_phys over [-2, 2] V");
    ref_daq.arm();
    ref_awg->trigger();
    com_daq->arm();
    com_awg->trigger();
    const auto a = ref_daq.fetch(2.0), c = com_daq->fetch(2.0);
    EXPECT_EQ(c.sample_rate_hz, a.sample_rate_hz);
    EXPECT_EQ(c.range_v[0], a.range_v[0]);
    ASSERT_EQ(c.v1.size(), a.v1.size());
    ASSERT_EQ(c.v2.size(), a.v2.size());
    for (int ch = 0; ch < 2; ++ch) {
      const auto& ref = ch == 0 ? a.v1 : a.v2;
      const auto& got = ch == 0 ? c.v1 : c.v2;
      if (softcal) {
        EXPECT_EQ(got, ref) << "shot " << shot << " v" << ch + 1;
        continue;
      }
      for (std::size_t i = 0; i < ref.size(); ++i) {
        const double code = std::round(ref[i] / (range / 2048.0));  // the Infiniium's 12-bit code
        ASSERT_EQ(got[i], comedi::linear_to_phys(static_cast<std::uint32_t>(code + 2048.0),
                                                 {-range, range}, 4095))
            << "shot " << shot << " v" << ch + 1 << " sample " << i;
      }
    }
  }
}

TEST(ComediDriver, SoftCalibratedShotsEqualTheInfiniiumPathSampleForSample) {
  expect_same_shots_as_infiniium(true);
}
TEST(ComediDriver, HardCalibratedShotsAreTheSameCodesThroughComediToPhys) {
  expect_same_shots_as_infiniium(false);
}

TEST(ComediDriver, ComedilibFormulas) {
  // lib/range.c: min + (max − min) · raw / maxdata; the ends are the range's ends.
  EXPECT_EQ(comedi::linear_to_phys(0, {-2, 2}, 4095), -2.0);
  EXPECT_EQ(comedi::linear_to_phys(4095, {-2, 2}, 4095), 2.0);
  EXPECT_DOUBLE_EQ(comedi::linear_to_phys(2048, {-10, 10}, 4095), -10.0 + 20.0 * 2048.0 / 4095.0);
  // lib/calib.c: Σ c_i (raw − origin)^i.
  comedi::Polynomial p{{0.5, 2e-3, 1e-7}, 2048.0};
  EXPECT_DOUBLE_EQ(comedi::polynomial_to_phys(2048, p), 0.5);
  EXPECT_DOUBLE_EQ(comedi::polynomial_to_phys(2058, p), 0.5 + 2e-2 + 1e-5);
  EXPECT_DOUBLE_EQ(comedi::polynomial_to_phys(2038, p), 0.5 - 2e-2 + 1e-5);
}

// ------------------------------------------------------------ faults
struct FaultCase {
  const char* name;
  FaultPlan::Kind kind;
  const char* message;
};

class ComediFaults : public ::testing::TestWithParam<FaultCase> {};

// The fault hits the second shot: the first is whole; the message names the
// device and how far the second got.
TEST_P(ComediFaults, ClearMessageNamingTheDevice) {
  const auto& fc = GetParam();
  auto b = bench12(3, 0.01, FaultPlan{fc.kind, 1});
  auto awg = awg_on(b, test::seeded_waveform(2, 1500, 1e6, 1.0));
  auto daq = comedi_on(b, "comedi-sim:///dev/comedi0");
  daq->configure(plan(1e6, 2000, 1.0));
  daq->arm();
  awg->trigger();
  EXPECT_EQ(daq->fetch(1.0).v1.size(), 2000u);
  daq->arm();
  awg->trigger();
  try {
    daq->fetch(0.2);
    FAIL() << fc.name << ": no error";
  } catch (const InstrumentError& e) {
    EXPECT_TRUE(contains(e.what(), "comedi-sim:///dev/comedi0 (pci-6110)")) << e.what();
    EXPECT_TRUE(contains(e.what(), fc.message)) << e.what();
  }
  if (fc.kind == FaultPlan::Kind::ComediDeviceGone) {  // and it stays gone
    try {
      daq->arm();
      FAIL() << "arm after the device went away";
    } catch (const InstrumentError& e) {
      EXPECT_TRUE(contains(e.what(), "device gone")) << e.what();
    }
  } else {  // the next shot works again
    daq->arm();
    awg->trigger();
    EXPECT_EQ(daq->fetch(1.0).v2.size(), 2000u);
  }
}

INSTANTIATE_TEST_SUITE_P(
    All, ComediFaults,
    ::testing::Values(FaultCase{"overrun", FaultPlan::Kind::ComediOverrun,
                                "buffer overrun after 666 of 2000 scans (EPIPE"},
                      FaultCase{"no_data", FaultPlan::Kind::ComediNoData,
                                "no samples for 0.2 s after 0 of 2000 scans (no trigger on PFI0?"},
                      FaultCase{"device_gone", FaultPlan::Kind::ComediDeviceGone,
                                "device gone after 666 of 2000 scans (ENODEV"}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(ComediDriver, NoTriggerIsATimeoutNotAHang) {
  auto b = bench12(3, 0.0);
  auto daq = comedi_on(b, "comedi-sim:///dev/comedi0?trigger=pfi3");
  daq->configure(plan(1e6, 100, 1.0));
  daq->arm();  // the AWG never fires
  try {
    daq->fetch(0.05);
    FAIL() << "no error";
  } catch (const InstrumentError& e) {
    EXPECT_TRUE(contains(e.what(), "no trigger on PFI3?")) << e.what();
  }
}

// ------------------------------------------------------------ the kernel's comedi_test driver
// Runs the real comedilib seam where /dev/comedi0 is the kernel's
// comedi_test (modprobe comedi_test; comedi_config /dev/comedi0 comedi_test
// 1000000,100000): its analog input streams a sawtooth on channel 0 and a
// square wave on channel 1 (±1 V by default) with a software start.
TEST(ComediKernel, ComediTestDriverStreamsThroughTheRealSeam) {
  struct stat st {};
  if (::stat("/dev/comedi0", &st) != 0)
    GTEST_SKIP()
        << "not run: no /dev/comedi0 on this machine (the kernel's comedi_test driver is not "
           "loaded: "
           "modprobe comedi_test and comedi_config /dev/comedi0 comedi_test need root and a kernel "
           "with Comedi; containers have neither)";
  std::unique_ptr<comedi::Board> board;
  try {
    board = comedi::open_comedilib_board("/dev/comedi0");
  } catch (const InstrumentError& e) {
    GTEST_SKIP() << "not run: /dev/comedi0 exists but cannot be opened: " << e.what();
  }
  if (board->driver_name() != "comedi_test")
    GTEST_SKIP()
        << "not run: /dev/comedi0 is a '" << board->driver_name()
        << "' board, not the kernel's comedi_test driver (this test drives no real hardware)";
  auto a = comedi::parse_address("comedi:///dev/comedi0?trigger=software&aref=rse");
  comedi::Driver daq(std::move(board), a);
  auto c = plan(1e5, 2000, 1.0);
  c.external_trigger = false;
  daq.configure(c);
  daq.arm();
  auto r = daq.fetch(5.0);
  ASSERT_EQ(r.v1.size(), 2000u);
  const auto [lo, hi] = std::minmax_element(r.v1.begin(), r.v1.end());
  EXPECT_LT(*lo, *hi);  // a sawtooth, not a constant
  for (double v : r.v1) EXPECT_LE(std::fabs(v), r.range_v[0] * 1.001);
}

}  // namespace
