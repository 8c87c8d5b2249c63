// The Red Pitaya STEMlab 125-14 driver against its simulated twin: the
// protocol's encodings (arbitrary list, big-endian float32 blocks), the
// decimation and gain choices, shots equal sample for sample to the
// Keysight 33500 + Infiniium path on an identical bench, the limits, and the
// faults (instrument error, reply timeout, link closed mid-block, malformed
// block), each with a message naming the step. Every driver case runs the
// same body over the in-process loopback and over TCP (the real
// TcpTransport against TcpServer). Nothing here has met a real board.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <random>

#include "drivers/infiniium/driver.hpp"
#include "drivers/keysight33500/driver.hpp"
#include "drivers/redpitaya/driver.hpp"
#include "drivers/sim/loopback_transport.hpp"
#include "drivers/sim/sim_awg.hpp"
#include "drivers/sim/sim_daq.hpp"
#include "drivers/sim/sim_redpitaya.hpp"
#include "drivers/sim/tcp_server.hpp"
#include "drivers/tcp_transport.hpp"
#include "tests/support/rc_physics.hpp"
#include "tests/support/scpi_link.hpp"

using namespace piezo;
using namespace piezo::drivers;
namespace rp = piezo::drivers::redpitaya;

namespace {

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// ------------------------------------------------------------ protocol
TEST(RedPitayaProtocol, OnlyRedPitayaServersAreAccepted) {
  EXPECT_TRUE(rp::accepts_idn("REDPITAYA,INSTR2020,0,01-02"));
  EXPECT_TRUE(rp::accepts_idn("RedPitaya, INSTR2014 ,0,01-02"));
  EXPECT_TRUE(rp::accepts_idn("REDPITAYA,INSTR2023,0,05-03"));
  EXPECT_FALSE(rp::accepts_idn("REDPITAYA,SOMETHING,0,1"));
  EXPECT_FALSE(rp::accepts_idn("KEYSIGHT TECHNOLOGIES,DSO9104A,1,1"));
  EXPECT_FALSE(rp::accepts_idn("garbage"));
}

TEST(RedPitayaProtocol, TheDecimationNeverSamplesSlowerThanAsked) {
  struct Case {
    double wanted;
    unsigned dec;
  };
  for (const Case& c : {Case{125e6, 1}, Case{100e6, 1}, Case{1e7, 8}, Case{15.625e6, 8},
                        Case{15.7e6, 1}, Case{1.953125e6, 64}, Case{1e6, 64}, Case{1e5, 1024},
                        Case{2000, 8192}, Case{1500, 65536}, Case{1, 65536}}) {
    auto r = rp::choose_decimation(c.wanted);
    ASSERT_TRUE(r) << c.wanted;
    EXPECT_EQ(r->decimation, c.dec) << c.wanted;
    EXPECT_EQ(r->sample_rate_hz, 125e6 / c.dec) << c.wanted;
    EXPECT_GE(r->sample_rate_hz, c.wanted * (1 - 1e-9));
  }
  EXPECT_FALSE(rp::choose_decimation(125.1e6));
  EXPECT_FALSE(rp::choose_decimation(0));
  EXPECT_FALSE(rp::choose_decimation(-5));
  EXPECT_FALSE(rp::choose_decimation(std::nan("")));
}

TEST(RedPitayaProtocol, TheGainIsTheSmallestRangeThatCovers) {
  EXPECT_EQ(rp::gain_for_range(0.3)->name, "LV");
  EXPECT_EQ(rp::gain_for_range(1.0)->name, "LV");
  EXPECT_EQ(rp::gain_for_range(1.01)->name, "HV");
  EXPECT_EQ(rp::gain_for_range(20.0)->name, "HV");
  EXPECT_EQ(rp::gain_for_range(20.5), nullptr);
  EXPECT_EQ(rp::gain_for_range(0.0), nullptr);
}

TEST(RedPitayaProtocol, TheTriggerDelayPlacesThePretrigger) {
  EXPECT_EQ(rp::trigger_delay_for(0), 8192);
  EXPECT_EQ(rp::trigger_delay_for(200), 7992);
  EXPECT_EQ(rp::trigger_delay_for(8192), 0);
  EXPECT_EQ(rp::trigger_delay_for(12000), -3808);
  EXPECT_EQ(rp::gain_command(2, "HV"), "ACQ:SOUR2:GAIN HV");
  EXPECT_EQ(rp::data_query(1), "ACQ:SOUR1:DATA?");
}

TEST(RedPitayaProtocol, TheArbitraryListRoundTripsEveryFloat) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> v(3000);
  for (auto& x : v) x = u(rng);
  v[0] = 1.0f, v[1] = -1.0f, v[2] = 0.0f, v[3] = 1e-30f;
  const std::string text = rp::encode_arb_list(v);
  std::vector<std::string> params;
  std::size_t at = 0;
  for (std::size_t c; (c = text.find(',', at)) != std::string::npos; at = c + 1)
    params.push_back(text.substr(at, c - at));
  params.push_back(text.substr(at));
  auto back = rp::decode_arb_list(params, 16384);
  ASSERT_TRUE(back);
  EXPECT_EQ(*back, v);                              // bit-exact
  EXPECT_FALSE(rp::decode_arb_list(params, 2999));  // more than the buffer
  EXPECT_FALSE(rp::decode_arb_list(std::vector<std::string>{"0.5", "x"}, 16384));
  EXPECT_FALSE(rp::decode_arb_list(std::vector<std::string>{}, 16384));
}

TEST(RedPitayaProtocol, BlocksAreBigEndianFloat32) {
  const float v[] = {1.0f, -0.5f};
  const std::vector<std::uint8_t> want = {0x3F, 0x80, 0x00, 0x00, 0xBF, 0x00, 0x00, 0x00};
  EXPECT_EQ(rp::encode_float_block_payload(v), want);
  auto back = rp::decode_float_block_payload(want);
  ASSERT_TRUE(back);
  EXPECT_EQ((*back)[0], 1.0f);
  EXPECT_EQ((*back)[1], -0.5f);
  EXPECT_FALSE(rp::decode_float_block_payload(std::vector<std::uint8_t>(7)));
}

// ------------------------------------------------------------ the twin, faulty on request
struct Fault {
  enum Kind { None, Error, Swallow, Garbage, CutBlock } kind = None;
  std::string header;  // pattern of the command that misbehaves
  std::string garbage;
};

class FaultyRp : public sim::SimRedPitaya {
 public:
  FaultyRp(std::shared_ptr<sim::SimBench> b, Fault f)
      : SimRedPitaya(std::move(b)), f_(std::move(f)) {}

 protected:
  bool command(const scpi::Command& c, const scpi::ProgramMessage& msg, sim::Reply& out) override {
    if (f_.kind == Fault::None || !scpi::match(f_.header, c.header))
      return SimRedPitaya::command(c, msg, out);
    switch (f_.kind) {
      case Fault::Error:
        push_error(-222, "Data out of range; simulated fault");
        return true;
      case Fault::Swallow:
        out.swallow = true;
        return true;
      case Fault::Garbage:
        append(out, f_.garbage + "\r\n");
        return true;
      case Fault::CutBlock: {  // the header and a third of the payload, then the link goes down
        sim::Reply full;
        SimRedPitaya::command(c, msg, full);
        out.bytes.assign(full.bytes.begin(),
                         full.bytes.begin() + static_cast<std::ptrdiff_t>(full.bytes.size() / 3));
        out.close_connection = true;
        return true;
      }
      case Fault::None:
        break;
    }
    return true;
  }

 private:
  Fault f_;
};

constexpr double kR1 = 3140.0, kC = 2.1e-9;
constexpr double kRate = 15.625e6;  // 125 MS/s / 8: a rate both paths sample at

std::shared_ptr<sim::SimBench> bench(std::uint64_t seed, double noise = 0.03) {
  return test::rc_bench(seed, noise, kR1, kC);
}

using Link = test::ScpiLink;
Link connect(const std::string& kind, std::shared_ptr<sim::ScpiDevice> dev) {
  return test::connect_link(kind, std::move(dev), "loop://rp");
}

ArbWaveform seeded_waveform(std::uint64_t seed, std::size_t n) {
  return test::seeded_waveform(seed, n, kRate, 0.7);
}

DaqConfig daq_config(std::size_t n, double rate = kRate) {
  DaqConfig c;
  c.sample_rate_hz = rate;
  c.record_length = n;
  c.pretrigger_samples = 100;
  c.range_v[0] = c.range_v[1] = 1.0;  // LV; and 2 V full scale on the Infiniium: the same LSB
  return c;
}

DaqRecord shot(Awg& awg, Daq& daq, const DaqConfig& c) {
  daq.configure(c);
  daq.arm();
  awg.output(true);
  awg.trigger();
  return daq.fetch(2.0);
}

class RedPitayaDriver : public ::testing::TestWithParam<std::string> {};

// With the whole buffer recorded (16384 samples) the two benches draw the
// same noise and quantise alike (LV: ±1 V in 14 bits; the Infiniium at 2 V
// full scale: the same 2^-13 V step, which float32 volts carry exactly).
TEST_P(RedPitayaDriver, WholeBufferShotsEqualTheKeysightPathSampleForSample) {
  auto rp_bench = bench(41), key_bench = bench(41);
  Link l = connect(GetParam(), std::make_shared<sim::SimRedPitaya>(rp_bench));
  auto roles = rp::open(std::move(l.transport));
  keysight33500::Driver key_awg(std::make_unique<sim::LoopbackTransport>(
      std::make_shared<sim::SimAwg>(key_bench), "loop://key"));
  infiniium::Driver key_daq(std::make_unique<sim::LoopbackTransport>(
      std::make_shared<sim::SimDaq>(key_bench), "loop://daq"));

  const DaqConfig c = daq_config(16384);
  const ArbWaveform w = seeded_waveform(6, c.record_length - c.pretrigger_samples);
  roles.awg->load(w);
  key_awg.load(w);
  for (int k = 0; k < 2; ++k) {
    const DaqRecord a = shot(*roles.awg, *roles.daq, c);
    const DaqRecord b = shot(key_awg, key_daq, c);
    ASSERT_EQ(a.v1.size(), 16384u);
    EXPECT_EQ(a.v1, b.v1) << "shot " << k;
    EXPECT_EQ(a.v2, b.v2) << "shot " << k;
    EXPECT_EQ(a.sample_rate_hz, kRate);
    EXPECT_EQ(a.pretrigger_samples, 100u);
    EXPECT_EQ(a.range_v[0], 1.0);
    double peak = 0;
    for (double x : a.v1) peak = std::max(peak, std::fabs(x));
    // The drive reached v1: peak_v at the high-impedance divider, within the
    // seeded noise (3 % of v1's std, about 6 mV; 0.05 V is some 8 sigma).
    EXPECT_NEAR(peak, 0.7, 0.05);
  }
}

// A shorter record is the start of the buffer. Without noise (whose level
// the simulator takes from the whole record) it equals the Infiniium's
// record of that length; the plan's 10 MS/s became 15.625 MS/s.
TEST_P(RedPitayaDriver, ShorterRecordsAreTheBufferStartAtTheStatedRate) {
  auto rp_bench = bench(5, 0.0), key_bench = bench(5, 0.0);
  Link l = connect(GetParam(), std::make_shared<sim::SimRedPitaya>(rp_bench));
  auto roles = rp::open(std::move(l.transport));
  keysight33500::Driver key_awg(std::make_unique<sim::LoopbackTransport>(
      std::make_shared<sim::SimAwg>(key_bench), "loop://key"));
  infiniium::Driver key_daq(std::make_unique<sim::LoopbackTransport>(
      std::make_shared<sim::SimDaq>(key_bench), "loop://daq"));
  const ArbWaveform w = seeded_waveform(7, 2900);
  roles.awg->load(w);
  key_awg.load(w);
  const DaqRecord a = shot(*roles.awg, *roles.daq, daq_config(3000, 1e7));
  EXPECT_EQ(roles.daq->rate().decimation, 8u);
  EXPECT_EQ(a.sample_rate_hz, kRate);
  const DaqRecord b = shot(key_awg, key_daq, daq_config(3000, kRate));
  EXPECT_EQ(a.v1, b.v1);
  EXPECT_EQ(a.v2, b.v2);
}

TEST_P(RedPitayaDriver, LimitsAreClearErrorsNamingThem) {
  Link l = connect(GetParam(), std::make_shared<sim::SimRedPitaya>(bench(2)));
  auto roles = rp::open(std::move(l.transport));
  auto message = [](const auto& f) -> std::string {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no error)";
  };
  std::string m = message([&] { roles.daq->configure(daq_config(20000)); });
  EXPECT_TRUE(contains(m, "record length 20000")) << m;
  EXPECT_TRUE(contains(m, "at most 16384 samples per channel")) << m;
  DaqConfig c = daq_config(1000);
  c.range_v[1] = 25;
  m = message([&] { roles.daq->configure(c); });
  EXPECT_TRUE(contains(m, "input 2 range")) << m;
  EXPECT_TRUE(contains(m, "±20 V (HV)")) << m;
  m = message([&] { roles.daq->configure(daq_config(1000, 200e6)); });
  EXPECT_TRUE(contains(m, "sample rate")) << m;
  c = daq_config(1000);
  c.coupling = Coupling::Ac;
  m = message([&] { roles.daq->configure(c); });
  EXPECT_TRUE(contains(m, "DC-coupled")) << m;
  m = message([&] { roles.awg->load(seeded_waveform(1, 16385)); });
  EXPECT_TRUE(contains(m, "16385 points")) << m;
  EXPECT_TRUE(contains(m, "16384")) << m;
  ArbWaveform w = seeded_waveform(1, 100);
  w.peak_v = 1.5;
  m = message([&] { roles.awg->load(w); });
  EXPECT_TRUE(contains(m, "peak voltage 1.5")) << m;
  EXPECT_THROW(roles.awg->trigger(), std::logic_error);  // nothing loaded
}

// HV: ±20 V in 14 bits, as float32 volts; the record states the range.
TEST_P(RedPitayaDriver, HighVoltageGainStatesItsRange) {
  Link l = connect(GetParam(), std::make_shared<sim::SimRedPitaya>(bench(3)));
  auto roles = rp::open(std::move(l.transport));
  roles.awg->load(seeded_waveform(8, 900));
  DaqConfig c = daq_config(1000);
  c.range_v[0] = 5.0;
  const DaqRecord r = shot(*roles.awg, *roles.daq, c);
  EXPECT_EQ(r.range_v[0], 20.0);
  EXPECT_EQ(r.range_v[1], 1.0);
  const double lsb = 20.0 / 8192;
  for (double x : r.v1) EXPECT_NEAR(x / lsb, std::round(x / lsb), 1e-3) << x;  // float32 of a code
}

// ------------------------------------------------------------ faults
Link faulty(const std::string& kind, Fault f) {
  return connect(kind, std::make_shared<FaultyRp>(bench(3), std::move(f)));
}

TEST_P(RedPitayaDriver, AnInstrumentErrorNamesTheStepAndCarriesItsText) {
  Link l = faulty(GetParam(), {Fault::Error, "ACQ:DEC", ""});
  auto roles = rp::open(std::move(l.transport));
  try {
    roles.daq->configure(daq_config(1000, 1e6));
    FAIL() << "configure() survived the instrument's error";
  } catch (const InstrumentError& e) {
    EXPECT_TRUE(contains(e.what(), "Red Pitaya, step 'decimation 64'")) << e.what();
    EXPECT_TRUE(contains(e.what(), "after 'ACQ:DEC 64'")) << e.what();
    EXPECT_TRUE(contains(e.what(), "-222,\"Data out of range; simulated fault\"")) << e.what();
  }
  Link g = faulty(GetParam(), {Fault::Error, "SOUR#:TRAC:DATA:DATA", ""});
  auto gen = rp::open(std::move(g.transport));
  try {
    gen.awg->load(seeded_waveform(1, 500));
    FAIL() << "load() survived the instrument's error";
  } catch (const InstrumentError& e) {
    EXPECT_TRUE(
        contains(e.what(), "step 'upload the waveform (SOUR1:TRAC:DATA:DATA, 16384 values)'"))
        << e.what();
  }
}

TEST_P(RedPitayaDriver, AReplyTimeoutNamesTheStep) {
  Link l = faulty(GetParam(), {Fault::Swallow, "ACQ:TRig:STAT", ""});
  auto roles = rp::open(std::move(l.transport));
  roles.awg->load(seeded_waveform(1, 900));
  try {
    shot(*roles.awg, *roles.daq, daq_config(1000));
    FAIL() << "fetch() survived a silent instrument";
  } catch (const TransportError& e) {
    EXPECT_EQ(e.kind(), TransportError::Kind::Timeout) << e.what();
    EXPECT_TRUE(contains(e.what(), "step 'wait for the trigger'")) << e.what();
    EXPECT_TRUE(contains(e.what(), "ACQ:TRig:STAT?")) << e.what();
  }
}

TEST_P(RedPitayaDriver, TheLinkClosedMidBlockNamesTheRead) {
  Link l = faulty(GetParam(), {Fault::CutBlock, "ACQ:SOUR2:DATA", ""});
  auto roles = rp::open(std::move(l.transport));
  roles.awg->load(seeded_waveform(1, 900));
  try {
    shot(*roles.awg, *roles.daq, daq_config(1000));
    FAIL() << "fetch() survived the link going down mid-block";
  } catch (const TransportError& e) {
    EXPECT_EQ(e.kind(), TransportError::Kind::Closed) << e.what();
    EXPECT_TRUE(contains(e.what(), "step 'read input 2 (ACQ:SOUR2:DATA?)'")) << e.what();
    EXPECT_TRUE(contains(e.what(), "65536 bytes expected")) << e.what();
  }
}

TEST_P(RedPitayaDriver, MalformedBlocksNameTheReadAndTheFault) {
  auto fails = [&](const std::string& garbage) -> std::string {
    Link l = faulty(GetParam(), {Fault::Garbage, "ACQ:SOUR1:DATA", garbage});
    auto roles = rp::open(std::move(l.transport));
    roles.awg->load(seeded_waveform(1, 900));
    try {
      shot(*roles.awg, *roles.daq, daq_config(1000));
    } catch (const InstrumentError& e) {
      return e.what();
    }
    return "(no error)";
  };
  std::string m = fails("{0.1,0.2}");  // ASCII where a block was asked for
  EXPECT_TRUE(contains(m, "step 'read input 1 (ACQ:SOUR1:DATA?)'")) << m;
  EXPECT_TRUE(contains(m, "malformed binary block")) << m;
  m = fails(std::string("#18\x3f\x80\x00\x00\x3f\x80\x00\x00", 11));  // two values, not the buffer
  EXPECT_TRUE(contains(m, "2 samples, expected the whole buffer of 16384")) << m;
  m = fails("#17abcdefg");
  EXPECT_TRUE(contains(m, "not a whole number of float32 values")) << m;
}

INSTANTIATE_TEST_SUITE_P(Transports, RedPitayaDriver, ::testing::Values("loopback", "tcp"),
                         [](const auto& info) { return info.param; });

// ------------------------------------------------------------ the twin itself
TEST(RedPitayaTwin, RefusesABenchThatIsNotFourteenBits) {
  sim::DaqImperfections imp;
  imp.adc_bits = 12;
  auto b = std::make_shared<sim::SimBench>(std::make_unique<test::RcPhysics>(kR1, kC), imp, 1);
  EXPECT_THROW(sim::SimRedPitaya{b}, std::invalid_argument);
}

// No ACQ:TRig AWG_PE, no record: the generator plays, the acquisition waits.
TEST(RedPitayaTwin, WithoutTheGeneratorTriggerTheAcquisitionWaits) {
  auto b = bench(9);
  auto roles = rp::open(std::make_unique<sim::LoopbackTransport>(
      std::make_shared<sim::SimRedPitaya>(b), "loop://rp"));
  roles.awg->load(seeded_waveform(2, 900));
  roles.daq->configure(daq_config(1000));
  roles.daq->arm();
  // output stays off: the burst reaches nothing, the trigger never comes
  roles.awg->trigger();
  EXPECT_THROW(roles.daq->fetch(0.05), InstrumentError);
}

}  // namespace
