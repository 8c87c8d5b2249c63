// The Tektronix AWG5000/7000 driver against its simulated twin: the REAL
// block format, the model table, a shot equal sample for sample to the
// Keysight path on an identical bench, and the faults (instrument error,
// reply timeout, link closed after the block, malformed reply), each with a
// message naming the step. Every driver case runs the same body over the
// in-process loopback and over TCP (the real TcpTransport against TcpServer).
// Nothing here has met a real instrument.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <random>

#include "drivers/infiniium/driver.hpp"
#include "drivers/keysight33500/driver.hpp"
#include "drivers/scpi_client.hpp"
#include "drivers/sim/loopback_transport.hpp"
#include "drivers/sim/sim_awg.hpp"
#include "drivers/sim/sim_daq.hpp"
#include "drivers/sim/sim_tektronix_awg.hpp"
#include "drivers/sim/tcp_server.hpp"
#include "drivers/tcp_transport.hpp"
#include "drivers/tektronix_awg/driver.hpp"
#include "tests/support/rc_physics.hpp"
#include "tests/support/scpi_link.hpp"

using namespace piezo;
using namespace piezo::drivers;
namespace tek = piezo::drivers::tektronix_awg;

namespace {

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// ------------------------------------------------------------ REAL format
TEST(TektronixProtocol, RealPointIsFloat32LittleEndianThenAMarkerByte) {
  const float v[] = {1.0f, -0.5f};
  const std::uint8_t m[] = {tek::kMarker1Bit, tek::kMarker2Bit};
  const auto b = tek::encode_real_points(v, m);
  // 1.0f = 0x3F800000, -0.5f = 0xBF000000, least significant byte first.
  const std::vector<std::uint8_t> want = {0x00, 0x00, 0x80, 0x3F, 0x40,
                                          0x00, 0x00, 0x00, 0xBF, 0x80};
  EXPECT_EQ(b, want);
}

TEST(TektronixProtocol, RealBlocksRoundTripAndRejectPartialPoints) {
  std::mt19937_64 rng(20);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> v(1001);
  for (auto& x : v) x = u(rng);
  const auto m = tek::trigger_markers(v.size());
  auto r = tek::decode_real_points(tek::encode_real_points(v, m));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->values, v);  // bit-exact: float32 in, float32 out
  EXPECT_EQ(r->markers, m);
  std::vector<std::uint8_t> odd(11);
  EXPECT_FALSE(tek::decode_real_points(odd));
}

TEST(TektronixProtocol, TriggerMarkerRisesWithThePointZeroAndEndsLow) {
  const auto m = tek::trigger_markers(10);
  for (std::size_t i = 0; i < 10; ++i) EXPECT_EQ(m[i], i < 5 ? tek::kMarker1Bit : 0) << i;
  EXPECT_EQ(tek::trigger_markers(1), std::vector<std::uint8_t>{tek::kMarker1Bit});
  EXPECT_TRUE(tek::trigger_markers(0).empty());
}

TEST(TektronixProtocol, ModelsAreChosenFromTheIdnReply) {
  const auto* a = tek::find_model("TEKTRONIX,AWG5014C,B051234,SCPI:99.0 FW:4.6.0.7");
  ASSERT_TRUE(a);
  EXPECT_EQ(a->channels, 4);
  EXPECT_EQ(a->dac_bits, 14);
  const auto* b = tek::find_model("Tektronix, AWG7122B ,B0,FW");
  ASSERT_TRUE(b);
  EXPECT_EQ(b->select_dac_bits, 8);  // markers need the 8-bit mode
  const auto* c = tek::find_model("TEKTRONIX,AWG5012,B0,FW");
  ASSERT_TRUE(c);
  EXPECT_EQ(c->idn_model, "AWG5012");  // not the B row
  EXPECT_FALSE(tek::find_model("TEKTRONIX,AWG70002A,B0,FW"));
  EXPECT_FALSE(tek::find_model("Keysight Technologies,33522B,MY1,1"));
  EXPECT_FALSE(tek::find_model("ACME,AWG5014C,1,1"));
  EXPECT_FALSE(tek::find_model("garbage"));
  for (const auto& m : tek::kModels) {
    EXPECT_TRUE(m.channels >= 1 && m.min_sample_rate_hz < m.max_sample_rate_hz &&
                m.min_points < m.max_points && m.min_amplitude_vpp < m.max_amplitude_vpp &&
                m.dac_bits > 0)
        << m.idn_model;
  }
}

// ------------------------------------------------------------ the twin, faulty on request
struct Fault {
  enum Kind { None, Error, Swallow, Garbage, Close } kind = None;
  std::string header;  // pattern (manual notation) of the command that misbehaves
  std::string garbage;
};

class FaultyTek : public sim::SimTektronixAwg {
 public:
  FaultyTek(std::shared_ptr<sim::SimBench> b, Fault f)
      : SimTektronixAwg(std::move(b)), f_(std::move(f)) {}

 protected:
  bool command(const scpi::Command& c, const scpi::ProgramMessage& msg, sim::Reply& out) override {
    if (f_.kind != Fault::None && scpi::match(f_.header, c.header)) {
      switch (f_.kind) {
        case Fault::Error:
          push_error(-222, "Data out of range; simulated fault");
          return true;
        case Fault::Swallow:
          out.swallow = true;
          return true;
        case Fault::Garbage:
          append(out, f_.garbage + "\n");
          return true;
        case Fault::Close:
          out.close_connection = true;
          return true;
        case Fault::None:
          break;
      }
    }
    return SimTektronixAwg::command(c, msg, out);
  }

 private:
  Fault f_;
};

constexpr double kR1 = 3140.0, kC = 2.1e-9;

std::shared_ptr<sim::SimBench> bench(std::uint64_t seed) { return test::rc_bench(seed, 0.03, kR1, kC); }

using Link = test::ScpiLink;
Link connect(const std::string& kind, std::shared_ptr<sim::ScpiDevice> dev) {
  return test::connect_link(kind, std::move(dev), "loop://tek");
}

ArbWaveform seeded_waveform(std::uint64_t seed, std::size_t n) {
  return test::seeded_waveform(seed, n, 1e7, 0.8);
}

DaqConfig daq_config() {
  DaqConfig c;
  c.sample_rate_hz = 1e7;
  c.record_length = 3000;
  c.pretrigger_samples = 100;
  c.range_v[0] = c.range_v[1] = 1.0;
  return c;
}

DaqRecord shot(Awg& awg, Daq& daq) {
  daq.configure(daq_config());
  daq.arm();
  awg.output(true);
  awg.trigger();
  return daq.fetch(2.0);
}

class TektronixDriver : public ::testing::TestWithParam<std::string> {};

// ------------------------------------------------------------ a shot, against the Keysight path
TEST_P(TektronixDriver, ShotsEqualTheKeysightPathSampleForSample) {
  auto tek_bench = bench(31), key_bench = bench(31);
  Link tl = connect(GetParam(), std::make_shared<sim::SimTektronixAwg>(tek_bench));
  Link dl = connect(GetParam(), std::make_shared<sim::SimDaq>(tek_bench));
  tek::Driver awg(std::move(tl.transport));
  infiniium::Driver daq(std::move(dl.transport));
  EXPECT_EQ(awg.model().idn_model, "AWG5014C");

  keysight33500::Driver key_awg(std::make_unique<sim::LoopbackTransport>(
      std::make_shared<sim::SimAwg>(key_bench), "loop://key"));
  infiniium::Driver key_daq(std::make_unique<sim::LoopbackTransport>(
      std::make_shared<sim::SimDaq>(key_bench), "loop://daq"));

  const ArbWaveform w = seeded_waveform(5, 2500);
  DaqRecord a;
  for (int load = 0; load < 2;
       ++load) {  // the second load replaces the waveform (DELete, then NEW)
    awg.load(w);
    key_awg.load(w);
    for (int k = 0; k < 2; ++k) {
      a = shot(awg, daq);
      const DaqRecord b = shot(key_awg, key_daq);
      ASSERT_EQ(a.v1.size(), 3000u);
      // Exact: both twins feed the bench the same float32 samples and the same
      // EMF (Tektronix: 2 x amplitude 0.8 Vpp into 50 ohm; Keysight: 1.6 Vpp at high Z).
      EXPECT_EQ(a.v1, b.v1) << "load " << load << " shot " << k;
      EXPECT_EQ(a.v2, b.v2) << "load " << load << " shot " << k;
    }
    // The records pass a 14-bit ADC, blind to a drive that differs below one
    // code; so the drive itself, as each twin handed it to the bench, too.
    std::scoped_lock lock(tek_bench->mutex(), key_bench->mutex());
    const sim::AwgState &ta = tek_bench->awg(), &ka = key_bench->awg();
    EXPECT_EQ(ta.arb, ka.arb);
    EXPECT_EQ(ta.vpp, ka.vpp);
    EXPECT_EQ(ta.offset_v, ka.offset_v);
    EXPECT_EQ(ta.arb_rate_hz, ka.arb_rate_hz);
    EXPECT_EQ(ta.output_on, ka.output_on);
  }
  // The drive's peak at the divider is peak_v: 0.8 V, give or take the 3 %
  // relative noise (about 0.01 V rms here; 0.05 V is five sigma).
  double peak = 0;
  for (double x : a.v1) peak = std::max(peak, std::fabs(x));
  EXPECT_NEAR(peak, 0.8, 0.05);
}

TEST_P(TektronixDriver, RefusesWhatTheModelCannotDo) {
  Link l = connect(GetParam(), std::make_shared<sim::SimTektronixAwg>(bench(1)));
  tek::Driver awg(std::move(l.transport));
  ArbWaveform w = seeded_waveform(2, 100);
  EXPECT_THROW(awg.load(w), std::invalid_argument);  // < 250 points
  w = seeded_waveform(2, 1000);
  w.sample_rate_hz = 1e6;  // below 10 MS/s
  EXPECT_THROW(awg.load(w), std::invalid_argument);
  w = seeded_waveform(2, 1000);
  w.peak_v = 5.0;  // above 4.5 Vpp into 50 ohm
  EXPECT_THROW(awg.load(w), std::invalid_argument);
  try {
    awg.trigger();  // nothing loaded: the AWG is stopped
    FAIL() << "trigger() without a waveform";
  } catch (const InstrumentError& e) {
    EXPECT_TRUE(contains(e.what(), "step 'trigger (*TRG)'")) << e.what();
    EXPECT_TRUE(contains(e.what(), "not waiting for a trigger")) << e.what();
  }
}

TEST_P(TektronixDriver, AKeysightIsNotATektronix) {
  Link l = connect(GetParam(), std::make_shared<sim::SimAwg>(bench(1)));
  try {
    tek::Driver awg(std::move(l.transport));
    FAIL() << "accepted a Keysight 33522B";
  } catch (const InstrumentError& e) {
    EXPECT_TRUE(contains(e.what(), "33522B")) << e.what();
    EXPECT_TRUE(contains(e.what(), "not a supported Tektronix")) << e.what();
  }
}

// ------------------------------------------------------------ faults
// Loads a waveform on a twin that misbehaves at `f.header`; returns the message thrown.
template <class E>
std::string load_fails_with(const std::string& kind, const Fault& f) {
  Link l = connect(kind, std::make_shared<FaultyTek>(bench(3), f));
  tek::Driver awg(std::move(l.transport));
  try {
    awg.load(seeded_waveform(4, 1000));
  } catch (const E& e) {
    return e.what();
  }
  ADD_FAILURE() << "load() survived the fault at " << f.header;
  return {};
}

TEST_P(TektronixDriver, AnInstrumentErrorNamesTheStepAndCarriesItsText) {
  const std::string m = load_fails_with<InstrumentError>(
      GetParam(), {Fault::Error, "[SOURce#:]VOLTage[:LEVel][:IMMediate][:AMPLitude]", ""});
  EXPECT_TRUE(contains(m, "step 'amplitude'")) << m;
  EXPECT_TRUE(contains(m, "SOURce1:VOLTage:AMPLitude 0.8")) << m;
  EXPECT_TRUE(contains(m, "-222,\"Data out of range; simulated fault\"")) << m;
}

TEST_P(TektronixDriver, AnErrorAfterTheBlockNamesTheUpload) {
  const std::string m =
      load_fails_with<InstrumentError>(GetParam(), {Fault::Error, "WLISt:WAVeform:DATA", ""});
  EXPECT_TRUE(contains(m, "step 'upload the waveform (WLISt:WAVeform:DATA)'")) << m;
  EXPECT_TRUE(contains(m, "<block of 5000 bytes>")) << m;  // 1000 points x 5 bytes
  EXPECT_TRUE(contains(m, "-222")) << m;
}

TEST_P(TektronixDriver, AReplyTimeoutNamesTheStep) {
  Link l = connect(GetParam(), std::make_shared<FaultyTek>(
                                   bench(3), Fault{Fault::Swallow, "AWGControl:RSTate", ""}));
  tek::Driver awg(std::move(l.transport));
  try {
    awg.load(seeded_waveform(4, 1000));
    FAIL() << "load() survived a silent instrument";
  } catch (const TransportError& e) {
    EXPECT_EQ(e.kind(), TransportError::Kind::Timeout) << e.what();
    EXPECT_TRUE(contains(e.what(), "step 'wait for the run state'")) << e.what();
    EXPECT_TRUE(contains(e.what(), "no reply within")) << e.what();
    EXPECT_TRUE(contains(e.what(), "AWGControl:RSTate?")) << e.what();
  }
}

TEST_P(TektronixDriver, TheLinkClosingAtTheBlockNamesTheUpload) {
  Link l = connect(GetParam(), std::make_shared<FaultyTek>(
                                   bench(3), Fault{Fault::Close, "WLISt:WAVeform:DATA", ""}));
  tek::Driver awg(std::move(l.transport));
  try {
    awg.load(seeded_waveform(4, 1000));
    FAIL() << "load() survived the link going down";
  } catch (const TransportError& e) {
    EXPECT_EQ(e.kind(), TransportError::Kind::Closed) << e.what();
    EXPECT_TRUE(contains(e.what(), "step 'upload the waveform (WLISt:WAVeform:DATA)'")) << e.what();
    EXPECT_TRUE(contains(e.what(), "closed the connection")) << e.what();
  }
}

TEST_P(TektronixDriver, AMalformedReplyNamesTheStepAndTheReply) {
  std::string m =
      load_fails_with<InstrumentError>(GetParam(), {Fault::Garbage, "AWGControl:RSTate", "BUSY"});
  EXPECT_TRUE(contains(m, "step 'wait for the run state'")) << m;
  EXPECT_TRUE(contains(m, "answered 'BUSY', expected 0, 1 or 2")) << m;
  m = load_fails_with<InstrumentError>(GetParam(), {Fault::Garbage, "WLISt:SIZE", "many"});
  EXPECT_TRUE(contains(m, "step 'look up the waveform list'")) << m;
  EXPECT_TRUE(contains(m, "'WLISt:SIZE?' answered 'many'")) << m;
}

INSTANTIATE_TEST_SUITE_P(Transports, TektronixDriver, ::testing::Values("loopback", "tcp"),
                         [](const auto& info) { return info.param; });

// The link dropped in the middle of the block, seen from the host: the
// transport fails while the block is being written. A scripted transport
// (in front of the twin) accepts the first third of the upload and then
// reports the connection closed, as a socket whose peer went away does.
class CutMidBlock : public Transport {
 public:
  explicit CutMidBlock(std::unique_ptr<Transport> inner) : inner_(std::move(inner)) {}
  std::string address() const override { return inner_->address(); }
  void send(std::span<const std::uint8_t> bytes) override {
    const std::string head(
        bytes.begin(),
        bytes.begin() + static_cast<std::ptrdiff_t>(std::min<std::size_t>(bytes.size(), 40)));
    if (head.starts_with("WLISt:WAVeform:DATA"))
      throw TransportError(TransportError::Kind::Closed,
                           address() + ": send: connection closed after " +
                               std::to_string(bytes.size() / 3) + " of " +
                               std::to_string(bytes.size()) + " bytes");
    inner_->send(bytes);
  }
  std::size_t receive(std::uint8_t* buf, std::size_t max, bool* eom) override {
    return inner_->receive(buf, max, eom);
  }
  void set_timeout(std::chrono::milliseconds t) override { inner_->set_timeout(t); }
  std::chrono::milliseconds timeout() const override { return inner_->timeout(); }
  using Transport::send;

 private:
  std::unique_ptr<Transport> inner_;
};

TEST(TektronixDriverFaults, TheLinkDroppedMidBlockNamesTheUpload) {
  auto inner = std::make_unique<sim::LoopbackTransport>(
      std::make_shared<sim::SimTektronixAwg>(bench(3)), "loop://tek");
  tek::Driver awg(std::make_unique<CutMidBlock>(std::move(inner)));
  try {
    awg.load(seeded_waveform(4, 1000));
    FAIL() << "load() survived the link dropping mid-block";
  } catch (const TransportError& e) {
    EXPECT_EQ(e.kind(), TransportError::Kind::Closed);
    EXPECT_TRUE(contains(e.what(), "step 'upload the waveform (WLISt:WAVeform:DATA)'")) << e.what();
    EXPECT_TRUE(contains(e.what(), "connection closed after")) << e.what();
  }
}

// ------------------------------------------------------------ the twin's trigger model
// Marker 1 is the DAQ's trigger: a waveform uploaded without it plays, but the DAQ never fires.
TEST(TektronixTwin, WithoutMarkerOneTheDaqIsNotTriggered) {
  auto b = bench(8);
  ScpiClient awg(std::make_unique<sim::LoopbackTransport>(std::make_shared<sim::SimTektronixAwg>(b),
                                                          "loop://tek"));
  infiniium::Driver daq(
      std::make_unique<sim::LoopbackTransport>(std::make_shared<sim::SimDaq>(b), "loop://daq"));
  std::vector<float> v(1000, 0.5f);
  std::vector<std::uint8_t> no_markers(v.size(), 0);
  awg.configure("WLISt:WAVeform:NEW \"X\",1000,REAL");
  awg.write_block("WLISt:WAVeform:DATA \"X\",0,1000,", tek::encode_real_points(v, no_markers));
  awg.check_errors("WLISt:WAVeform:DATA");
  for (const char* c : {"SOURce1:WAVeform \"X\"", "SOURce1:FREQuency 1e7",
                        "AWGControl:RMODe TRIGgered", "OUTPut1:STATe ON", "AWGControl:RUN"})
    awg.configure(c);
  EXPECT_EQ(awg.query("AWGControl:RSTate?"), "1");
  daq.configure(daq_config());
  daq.arm();
  awg.write("*TRG");
  awg.check_errors("*TRG");
  EXPECT_THROW(daq.fetch(0.05), InstrumentError);  // "no trigger / acquisition not done"
}

}  // namespace
