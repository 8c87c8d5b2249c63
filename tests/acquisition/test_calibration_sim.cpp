// Calibration standards on the simulated bench: the open/short/load circuits
// against circuit algebra (the same fixture as the tube), SIM:DUT through the
// real SCPI drivers (in-process and over TCP), the runner writing calibration
// shots with their roles and a ranged channel 2, and the technician prompt of
// a real bench.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <filesystem>

#include "acquisition/calibration_plan.hpp"
#include "acquisition/capture_file.hpp"
#include "acquisition/divider_state_space.hpp"
#include "acquisition/runner.hpp"
#include "acquisition/sim_setup.hpp"
#include "drivers/keysight33500/driver.hpp"
#include "drivers/sim/sim_awg.hpp"
#include "drivers/sim/sim_daq.hpp"
#include "drivers/sim/tcp_server.hpp"
#include "tests/support/rc_physics.hpp"

namespace {
using namespace piezo;
using cd = std::complex<double>;
using K = drivers::sim::DutSelection::Kind;
namespace fs = std::filesystem;

model::ModalPortModel empty_port() { return {}; }  // a standard never reads the port

acq::BenchCircuit fixture(double rs, double cp, double rd) {
  acq::BenchCircuit c;
  c.r1_ohm = 3234.0;
  c.series_resistance_ohm = rs;
  c.parallel_capacitance_f = cp;
  c.daq_input_resistance_ohm = rd;
  return c;
}

cd expected(const acq::BenchCircuit& c, double w) {
  const auto& d = c.dut;
  cd yb = 0;  // the branch from v2 through the lead
  if (d.kind == K::Short)
    yb = c.series_resistance_ohm > 0 ? 1.0 / c.series_resistance_ohm : cd(INFINITY);
  if (d.kind == K::Load)
    yb = 1.0 / (c.series_resistance_ohm + d.load_ohm / cd(1.0, w * d.load_ohm * d.load_parallel_f));
  if (std::isinf(yb.real())) return 0.0;
  const cd y =
      cd(std::isfinite(c.daq_input_resistance_ohm) ? 1.0 / c.daq_input_resistance_ohm : 0.0,
         w * c.parallel_capacitance_f) +
      yb;
  return 1.0 / (1.0 + c.r1_ohm * y);
}

TEST(CalibrationStandards, CircuitsFollowCircuitAlgebra) {
  const drivers::sim::DutSelection duts[] = {
      {K::Open, 0, 0}, {K::Short, 0, 0}, {K::Load, 1000, 0}, {K::Load, 470, 1e-9}};
  for (const auto& c0 : {fixture(10, 150e-12, 1e6), fixture(0, 150e-12, INFINITY),
                         fixture(12, 0, INFINITY), fixture(0, 0, 1e6)}) {
    for (const auto& d : duts) {
      auto c = c0;
      c.dut = d;
      if (d.kind == K::Short && c.series_resistance_ohm == 0 && c.parallel_capacitance_f == 0)
        continue;
      acq::DividerStateSpace ss(empty_port(), c);
      for (double f : {1e3, 50e3, 2e6}) {
        const double w = 2 * M_PI * f;
        const cd want = expected(c, w), got = ss.transfer(w);
        EXPECT_LT(std::abs(got - want), 1e-9 * std::max(1.0, std::abs(want)))
            << int(d.kind) << " Rs " << c.series_resistance_ohm << " Cp "
            << c.parallel_capacitance_f << " f " << f;
      }
    }
  }
  auto bad = fixture(1, 1e-10, INFINITY);
  bad.dut = {K::Load, -5, 0};
  EXPECT_THROW(acq::DividerStateSpace(empty_port(), bad), std::invalid_argument);
}

TEST(CalibrationStandards, LoadStepResponseMatchesItsTransfer) {
  // Time domain against the frequency response: a 30 kHz sine into the load with
  // lead resistance and both capacitances (two states), after the transient.
  auto c = fixture(10, 150e-12, 1e6);
  c.dut = {K::Load, 1000, 1e-9};
  acq::DividerStateSpace ss(empty_port(), c);
  const double fs = 1e7, f = 30e3, w = 2 * M_PI * f;
  drivers::sim::PiecewiseLinear pl;
  std::vector<double> t;
  for (int k = 0; k < 4000; ++k) {
    pl.t.push_back(k / fs);
    pl.v.push_back(std::sin(w * k / fs));
  }
  for (int k = 3000; k < 4000; ++k) t.push_back(k / fs);
  const auto v2 = ss.simulate(pl, t);
  double re = 0, im = 0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    re += v2[k] * std::sin(w * t[k]);
    im += v2[k] * std::cos(w * t[k]);
  }
  const cd got = cd(re, im) * (2.0 / double(t.size()));
  // The input is the sine's piecewise-linear interpolation, whose component at f
  // is sinc²(πf/fs) of the sine (1 − 3e-5 here); its images at k·fs ± f come back
  // on sampling, weighted by sinc² there (~1e-5) and by the transfer at 10 MHz.
  const double x = M_PI * f / fs, sinc2 = std::pow(std::sin(x) / x, 2);
  EXPECT_LT(std::abs(got - sinc2 * ss.transfer(w)), 3e-7);
}

// SIM:DUT through the Keysight driver's own SCPI session, over a given transport.
void exercise_sim_dut(drivers::keysight33500::Driver& awg, drivers::sim::SimBench& bench) {
  awg.scpi().configure("SIMulation:DUT LOAD,1000,1e-10");
  EXPECT_EQ(awg.scpi().query("SIM:DUT?"), "LOAD,1000,1e-10");
  EXPECT_EQ(bench.dut().kind, K::Load);
  awg.scpi().configure("SIM:DUT OPEN");
  EXPECT_EQ(awg.scpi().query("SIM:DUT?"), "OPEN");
  try {
    awg.scpi().configure("SIM:DUT MAGIC");
    FAIL() << "accepted";
  } catch (const drivers::InstrumentError& e) {
    EXPECT_NE(std::string(e.what()).find("-224"), std::string::npos) << e.what();
  }
  EXPECT_THROW(awg.scpi().configure("SIM:DUT LOAD"), drivers::InstrumentError);     // -109
  EXPECT_THROW(awg.scpi().configure("SIM:DUT LOAD,-3"), drivers::InstrumentError);  // -222
  EXPECT_THROW(awg.scpi().configure("SIM:DUT SHORT,5"), drivers::InstrumentError);  // -109
  EXPECT_EQ(bench.dut().kind, K::Open);  // refused commands change nothing
  awg.scpi().configure("SIM:DUT TUBE");
  EXPECT_EQ(bench.dut().kind, K::Tube);
}

std::shared_ptr<drivers::sim::SimBench> fe_bench() {
  acq::SimSpec spec;
  spec.effects.parallel_capacitance_f = 100e-12;
  spec.effects.series_resistance_ohm = 5;
  spec.modes = 8;
  return acq::make_sim_bench(spec, 3140.0);
}

TEST(CalibrationStandards, SimDutInProcessAndOverTcp) {
  auto sim = fe_bench();
  auto local = acq::open_bench({"sim", std::nullopt}, sim);
  EXPECT_TRUE(acq::is_simulated_instrument(local));
  exercise_sim_dut(dynamic_cast<drivers::keysight33500::Driver&>(*local.awg), *sim);

  auto sim2 = fe_bench();
  drivers::sim::TcpServer awg_srv(std::make_shared<drivers::sim::SimAwg>(sim2), "127.0.0.1", 0);
  drivers::sim::TcpServer daq_srv(std::make_shared<drivers::sim::SimDaq>(sim2), "127.0.0.1", 0);
  awg_srv.start();
  daq_srv.start();
  auto remote = acq::open_bench({"tcp://127.0.0.1:" + std::to_string(awg_srv.port()),
                                 "tcp://127.0.0.1:" + std::to_string(daq_srv.port())});
  EXPECT_TRUE(acq::is_simulated_instrument(remote));
  exercise_sim_dut(dynamic_cast<drivers::keysight33500::Driver&>(*remote.awg), *sim2);
}

fs::path tmp_dir() {
  auto d =
      fs::temp_directory_path() / ("piezobench-calsim-" + std::to_string(::getpid()) + "-" +
                                   ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

acq::MeasurementPlan short_plan() {
  acq::MeasurementPlan p;
  p.samples = 4000;
  p.pretrigger_samples = 100;
  p.shots = 2;
  p.setup.divider_r1_ohm = 3140.0;
  return p;
}

TEST(CalibrationRun, StandardsFirstWithRolesAndARangedChannelTwo) {
  auto sim = fe_bench();
  auto bench = acq::open_bench({"sim", std::nullopt}, sim);
  acq::RunnerOptions ro;
  ro.calibration = acq::parse_calibration_list("short, open,load", 820.0, 2.2e-10);
  ro.connect_standard = acq::make_standard_connector(bench, nullptr);
  std::vector<std::string> stages;
  const auto dir = tmp_dir();
  const auto res = acq::run_measurement(bench, short_plan(), dir / "c.h5", ro,
                                        [&](const acq::Progress& p) { stages.push_back(p.stage); });
  EXPECT_EQ(res.shots_written, 8);
  EXPECT_EQ(sim->dut().kind, K::Tube);  // the transducer is back for the dut shots
  const auto cap = acq::read_capture(dir / "c.h5");
  const acq::Role want[] = {acq::Role::Short, acq::Role::Short, acq::Role::Open, acq::Role::Open,
                            acq::Role::Load,  acq::Role::Load,  acq::Role::Dut,  acq::Role::Dut};
  ASSERT_EQ(cap.shots.size(), 8u);
  for (std::size_t k = 0; k < 8; ++k) EXPECT_EQ(cap.shots[k].role, want[k]) << k;
  EXPECT_EQ(cap.shots[4].load_ohm, 820.0);
  EXPECT_EQ(cap.shots[4].load_parallel_f, 2.2e-10);
  EXPECT_FALSE(cap.shots[6].load_ohm);
  // The short's channel 2 was ranged to its millivolts: no single full scale, and
  // a fine resolution (steps of the 14-bit code well below a millivolt).
  EXPECT_FALSE(cap.shots[0].daq_range_v);
  EXPECT_TRUE(cap.shots[6].daq_range_v);
  double step = INFINITY;
  for (std::size_t i = 1; i < cap.shots[0].v2.size(); ++i) {
    const double d = std::abs(cap.shots[0].v2[i] - cap.shots[0].v2[i - 1]);
    if (d > 0) step = std::min(step, d);
  }
  EXPECT_LT(step, 2e-6);
  EXPECT_NE(std::find(stages.begin(), stages.end(), "connect short"), stages.end());
  EXPECT_NE(std::find(stages.begin(), stages.end(), "range short"), stages.end());
  EXPECT_NE(std::find(stages.begin(), stages.end(), "connect dut"), stages.end());
  fs::remove_all(dir);
}

// A real bench: the technician is asked; declining cancels, the shots so far stay.
class FakeAwg : public drivers::Awg {
 public:
  std::string identity() const override { return "Keysight Technologies,33522B,MY0000,4.0"; }
  void load(const drivers::ArbWaveform&) override {}
  void output(bool) override {}
  void trigger() override {}
};

TEST(CalibrationRun, RealBenchAsksTheTechnician) {
  acq::Bench real;
  real.awg = std::make_unique<FakeAwg>();
  EXPECT_FALSE(acq::is_simulated_instrument(real));
  EXPECT_THROW(acq::make_standard_connector(real, nullptr), std::invalid_argument);
  std::vector<std::string> asked;
  auto connect = acq::make_standard_connector(real, [&](const std::string& text) {
    asked.push_back(text);
    return asked.size() < 2;  // connects the first standard, cancels at the second
  });
  const auto steps = acq::parse_calibration_list("open,load", 1000.0);
  EXPECT_TRUE(connect(steps[0]));
  EXPECT_FALSE(connect(steps[1]));
  ASSERT_EQ(asked.size(), 2u);
  EXPECT_NE(asked[0].find("OPEN"), std::string::npos);
  EXPECT_NE(asked[1].find("1000 ohm"), std::string::npos);

  // Through the runner on the simulator with a declining operator: cancelled, nothing after.
  auto sim = fe_bench();
  auto bench = acq::open_bench({"sim", std::nullopt}, sim);
  acq::RunnerOptions ro;
  ro.calibration = acq::parse_calibration_list("open,short");
  int calls = 0;
  ro.connect_standard = [&](const acq::CalibrationStep&) { return ++calls < 2; };
  const auto dir = tmp_dir();
  const auto res = acq::run_measurement(bench, short_plan(), dir / "c.h5", ro);
  EXPECT_TRUE(res.cancelled);
  EXPECT_EQ(res.shots_written, 2);  // the open's shots
  fs::remove_all(dir);
}

TEST(CalibrationRun, BadListsAreRefusedByName) {
  auto msg = [](const char* list, double load = 1000.0) {
    try {
      acq::parse_calibration_list(list, load);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(msg("open,shrt").find("'shrt'"), std::string::npos);
  EXPECT_NE(msg("open,open").find("twice"), std::string::npos);
  EXPECT_NE(msg("dut").find("'dut'"), std::string::npos);
  EXPECT_NE(msg("").find("empty"), std::string::npos);
  EXPECT_NE(msg("load", -1).find("--load-ohm"), std::string::npos);
  EXPECT_EQ(acq::channel_range_for({0.0031, -0.001}, 1.25), 0.005);
  EXPECT_EQ(acq::channel_range_for({0.2374}, 1.25), 0.5);
  EXPECT_EQ(acq::channel_range_for({0.99}, 1.25), 1.25);
}

}  // namespace
