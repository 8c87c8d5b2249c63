// `piezobench measure` on the embedded simulated bench and through
// `piezobench sim-instrument` over TCP: same SCPI drivers, same simulated
// instruments, so the two captures must be equal sample for sample; and
// over TCP with the AWG in the Tektronix dialect (its own driver, chosen
// from *IDN?), equal to the embedded bench too; and a Red Pitaya twin at
// one address (both roles, no --daq), equal for a plan it can follow.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "acquisition/capture_file.hpp"
#include "tests/support/run_cli.hpp"

extern char** environ;
namespace fs = std::filesystem;
using namespace piezo;

namespace {
fs::path tmp_dir() {
  auto d = fs::temp_directory_path() / ("piezobench-measure-" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

int free_port_pair() {  // two consecutive free ports (AWG, DAQ)
  for (int attempt = 0; attempt < 50; ++attempt) {
    int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
    socklen_t len = sizeof a;
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
    int port = ntohs(a.sin_port);
    ::close(fd);
    int fd2 = ::socket(AF_INET, SOCK_STREAM, 0);
    a.sin_port = htons(static_cast<uint16_t>(port + 1));
    bool ok = port < 65000 && ::bind(fd2, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    ::close(fd2);
    if (ok) return port;
  }
  return 0;
}

TEST(CliMeasure, SeedLabMeasurementOnTheEmbeddedBench) {
  auto out = tmp_dir() / "lab.h5";
  auto r = test::run_cli("measure --instrument sim --excitation exp_decay --amplitude 1 --decay 3000 "
                         "--samples 20000 --rate 1e7 --shots 2 --noise 0.03 --seed 9 --overwrite --json --out " +
                         out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["shots_written"], 2);
  auto cap = acq::read_capture(out);
  ASSERT_EQ(cap.shots.size(), 2u);
  EXPECT_EQ(cap.shots[0].samples(), 20000u);
  EXPECT_EQ(cap.setup.divider_r1_ohm, 3140.0);
}

TEST(CliMeasure, BadEffectIsBadInput) {
  auto out = tmp_dir() / "bad.h5";
  auto r = test::run_cli("measure --effect no_such_effect=1 --out " + out.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("no_such_effect"), std::string::npos);
  r = test::run_cli("measure --effect series_resistance=-5 --out " + out.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bounds"), std::string::npos);
}

// Serves the simulated bench with `sim-instrument` (AWG dialect `dialect`),
// measures over TCP with the driver the AWG's *IDN? chooses, measures the same
// plan on the embedded bench (Keysight twin, in-process), and compares.
// Returns the TCP run's bench description (which names the AWG's *IDN?).
// `plan` is the measurement plan's options; the instrument is up when `up_port`
// (PORT + up_offset: the DAQ's port, or the one port of a Red Pitaya) accepts.
// `sim` is the simulated bench's option and its value, given to both benches.
std::string expect_tcp_equals_in_process(
    const char* dialect, const std::string& plan = " --samples 5000 --shots 2", int up_offset = 1,
    const std::array<std::string, 2>& sim = {"--effect", "parallel_capacitance=100e-12"}) {
  const int port = free_port_pair();
  EXPECT_GT(port, 0);
  std::string exe = PIEZO_CLI, p = std::to_string(port);
  const char* argv[] = {exe.c_str(),    "sim-instrument", "--host",    "127.0.0.1",
                        "--port",       p.c_str(),        "--seconds", "60",
                        "--noise",      "0.05",           "--seed",    "17",
                        sim[0].c_str(), sim[1].c_str(),   "--dialect", dialect,
                        nullptr};
  pid_t pid = 0;
  EXPECT_EQ(posix_spawn(&pid, exe.c_str(), nullptr, nullptr, const_cast<char**>(argv), environ), 0);
  // Wait until both ports accept connections.
  for (int i = 0; i < 200; ++i) {
    int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<uint16_t>(port + up_offset));
    bool up = ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    ::close(fd);
    if (up) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  auto dir = tmp_dir() / dialect;
  fs::create_directories(dir);
  const std::string out = plan + " --overwrite --out ";
  auto tcp = test::run_cli("measure --json --instrument tcp://127.0.0.1:" + p + out + (dir / "tcp.h5").string());
  ::kill(pid, SIGTERM);
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_EQ(tcp.exit_code, 0) << tcp.err;
  auto local = test::run_cli("measure --instrument sim --noise 0.05 --seed 17 " + sim[0] + " " +
                             sim[1] + out + (dir / "local.h5").string());
  EXPECT_EQ(local.exit_code, 0) << local.err;
  if (tcp.exit_code != 0 || local.exit_code != 0) return {};
  auto a = acq::read_capture(dir / "tcp.h5");
  auto b = acq::read_capture(dir / "local.h5");
  EXPECT_EQ(a.shots.size(), 2u);
  EXPECT_EQ(b.shots.size(), 2u);
  for (std::size_t k = 0; k < std::min<std::size_t>({2, a.shots.size(), b.shots.size()}); ++k) {
    EXPECT_EQ(a.shots[k].sample_rate_hz, b.shots[k].sample_rate_hz) << dialect << " shot " << k;
    EXPECT_EQ(a.shots[k].v1.size(), b.shots[k].v1.size()) << dialect << " shot " << k;
    EXPECT_EQ(a.shots[k].v1, b.shots[k].v1) << dialect << " shot " << k;
    EXPECT_EQ(a.shots[k].v2, b.shots[k].v2) << dialect << " shot " << k;
  }
  return nlohmann::json::parse(tcp.out)["bench"].get<std::string>();
}
}  // namespace

TEST(CliMeasure, SimInstrumentOverTcpEqualsInProcess) {
  const std::string bench = expect_tcp_equals_in_process("keysight");
  EXPECT_NE(bench.find("33522B"), std::string::npos) << bench;
}

// Issue 33 item 4: `sim-instrument --disturbance` serves the disturbed bench.
// Offset, hum, pink noise and jitter draw from the bench's own disturbance
// generator, one draw per acquisition, and need nothing of the capture (drift
// does: a SCPI client does not send the shot count), so the capture over TCP
// equals the embedded bench's with the same string, sample for sample (that
// the embedded bench applies them: test_cli_disturbance.cpp).
TEST(CliMeasure, SimInstrumentWithDisturbancesOverTcpEqualsInProcess) {
  const std::string bench = expect_tcp_equals_in_process(
      "keysight", " --samples 5000 --shots 2", 1,
      {"--disturbance", "offset=0.005,hum=0.005,mains=60,pink=1,jitter=0.5"});
  EXPECT_NE(bench.find("33522B"), std::string::npos) << bench;
}

// Issue 20: the Tektronix AWG5000 driver, end to end over TCP against its
// twin, records what the embedded (Keysight) bench records, sample for
// sample: both twins hand the bench the same float32 samples (REAL format
// and FORMat:BORDer SWAPped blocks alike) and the same EMF (Tektronix:
// amplitude peak_v Vpp into 50 ohm, doubled at the high-impedance divider;
// Keysight: 2 peak_v Vpp with OUTPut:LOAD INFinity).
TEST(CliMeasure, TektronixTwinOverTcpEqualsInProcess) {
  const std::string bench = expect_tcp_equals_in_process("tektronix");
  EXPECT_NE(bench.find("TEKTRONIX,AWG5014C"), std::string::npos) << bench;
}

// Issue 20: the Red Pitaya STEMlab 125-14 twin at ONE address: `measure
// --instrument tcp://127.0.0.1:PORT` with no --daq runs the redpitaya driver
// for both roles. The plan is one both benches follow exactly: the whole
// 16384-sample buffer (the twin always records all of it; a shorter record
// is its start, but the simulator scales its noise by the whole record's
// std, so only whole-buffer shots draw the same noise), 15.625 MS/s (125
// MS/s / 8, so no rate is rounded up) and a ±1 V range (LV: 2^-13 V steps
// in 14 bits, the embedded Infiniium's step at 2 V full scale; float32 volts
// carry them exactly). Then the captures are equal sample for sample.
TEST(CliMeasure, RedPitayaTwinAtOneAddressEqualsInProcess) {
  const std::string bench = expect_tcp_equals_in_process(
      "redpitaya", " --samples 16384 --pretrigger 200 --rate 15.625e6 --range 1 --amplitude 0.8 --shots 2",
      0);
  EXPECT_NE(bench.find("REDPITAYA,INSTR2020"), std::string::npos) << bench;
  EXPECT_NE(bench.find("one instrument, both roles"), std::string::npos) << bench;
}

// The default plan's 20000 samples exceed the board's buffers: clear errors naming the limit.
TEST(CliMeasure, RedPitayaRefusesMoreSamplesThanItsBuffer) {
  const int port = free_port_pair();
  ASSERT_GT(port, 0);
  std::string exe = PIEZO_CLI, p = std::to_string(port);
  const char* argv[] = {exe.c_str(), "sim-instrument", "--host", "127.0.0.1", "--port", p.c_str(),
                        "--seconds", "60", "--dialect", "redpitaya", nullptr};
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, exe.c_str(), nullptr, nullptr, const_cast<char**>(argv), environ), 0);
  test::CliResult r;
  for (int i = 0; i < 200; ++i) {  // until the port accepts
    r = test::run_cli("measure --instrument tcp://127.0.0.1:" + p + " --amplitude 0.5 --overwrite --out " +
                      (tmp_dir() / "rp-too-long.h5").string());
    if (r.err.find("connect") == std::string::npos) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  // The runner loads the generator first: its 19800 points (after the
  // pretrigger) exceed the generator's buffer of the same size.
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("19800 points (1..16384: the STEMlab 125-14's generator buffer)"), std::string::npos)
      << r.err;
  // A waveform that fits, a record that does not: the acquisition's limit.
  r = test::run_cli("measure --instrument tcp://127.0.0.1:" + p +
                    " --amplitude 0.5 --pretrigger 10000 --overwrite --out " + (tmp_dir() / "rp-too-long.h5").string());
  ::kill(pid, SIGTERM);
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("record length 20000 samples: the STEMlab 125-14 holds at most 16384 samples per channel"),
            std::string::npos)
      << r.err;
}

TEST(CliMeasure, UnknownDialectIsBadInput) {
  auto r = test::run_cli("sim-instrument --dialect rigol --seconds 1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("dialect"), std::string::npos) << r.err;
}

// Issue 20 item 2: `measure --daq comedi-sim:///dev/comediN` runs the Comedi
// driver against the simulated PCI-6110 on the embedded bench. A plan the
// board follows exactly (no pretrigger: a Comedi command starts at its
// trigger; 5 MS/s; ±2 V, one of its ranges), a 12-bit bench (its
// converter), the soft calibration's ideal polynomial: the capture equals
// the embedded Keysight + Infiniium bench's sample for sample.
TEST(CliMeasure, ComediBoardOnTheEmbeddedBenchEqualsInProcess) {
  auto dir = tmp_dir() / "comedi";
  fs::create_directories(dir);
  const std::string plan =
      " --adc-bits 12 --samples 20000 --pretrigger 0 --rate 5e6 --range 2 --shots 2 --noise 0.05 "
      "--seed 17 --effect parallel_capacitance=100e-12 --overwrite --out ";
  auto com = test::run_cli(
      "measure --json --instrument sim --daq 'comedi-sim:///dev/comedi0?trigger=pfi0&softcal=1'" +
      plan + (dir / "comedi.h5").string());
  ASSERT_EQ(com.exit_code, 0) << com.err;
  EXPECT_NE(nlohmann::json::parse(com.out)["bench"].get<std::string>().find("COMEDI,pci-6110"),
            std::string::npos)
      << com.out;
  auto local = test::run_cli("measure --instrument sim" + plan + (dir / "local.h5").string());
  ASSERT_EQ(local.exit_code, 0) << local.err;
  auto a = acq::read_capture(dir / "comedi.h5");
  auto b = acq::read_capture(dir / "local.h5");
  ASSERT_EQ(a.shots.size(), 2u);
  ASSERT_EQ(b.shots.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(a.shots[k].v1, b.shots[k].v1) << "shot " << k;
    EXPECT_EQ(a.shots[k].v2, b.shots[k].v2) << "shot " << k;
  }
  // The demo's next step, the update, from each capture: the same result
  // (all but the capture's name and the time taken), converged.
  auto ua = test::run_cli("update --json " + (dir / "comedi.h5").string());
  auto ub = test::run_cli("update --json " + (dir / "local.h5").string());
  ASSERT_EQ(ua.exit_code, 0) << ua.err;
  ASSERT_EQ(ub.exit_code, 0) << ub.err;
  auto ja = nlohmann::json::parse(ua.out), jb = nlohmann::json::parse(ub.out);
  EXPECT_TRUE(ja["converged"].get<bool>()) << ua.out;
  for (auto* j : {&ja, &jb}) {
    j->erase("capture");
    j->erase("seconds");
  }
  EXPECT_EQ(ja, jb);
}

// The Tektronix twin with the Comedi board: the AWG at 10 MS/s (its
// minimum), the board at 5 MS/s (its maximum; command_test rounds the scan
// period and the capture states the rate). The default plan's pretrigger is
// refused with the reason; a plan the 6110E cannot range is refused too.
TEST(CliMeasure, TektronixWithComediBoardAndItsRefusals) {
  auto dir = tmp_dir() / "tek-comedi";
  fs::create_directories(dir);
  const std::string daq = " --daq 'comedi-sim:///dev/comedi0' --adc-bits 12 --overwrite --out " +
                          (dir / "t.h5").string();
  auto r = test::run_cli(
      "measure --json --instrument 'sim?awg=tektronix' --samples 3000 --pretrigger 0 --shots 2" +
      daq);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(nlohmann::json::parse(r.out)["bench"].get<std::string>().find("TEKTRONIX,AWG5014C"),
            std::string::npos)
      << r.out;
  auto cap = acq::read_capture(dir / "t.h5");
  ASSERT_EQ(cap.shots.size(), 2u);
  EXPECT_EQ(cap.shots[0].sample_rate_hz, 5e6);
  EXPECT_EQ(cap.shots[0].samples(), 3000u);
  r = test::run_cli("measure --instrument 'sim?awg=tektronix' --samples 3000" + daq);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(
      r.err.find(
          "a Comedi command starts at its trigger: no samples before it (pretrigger 200; use 0)"),
      std::string::npos)
      << r.err;
  r = test::run_cli(
      "measure --instrument sim --daq 'comedi-sim:///dev/comedi0' --overwrite --pretrigger 0 "
      "--out " +
      (dir / "b.h5").string());  // a 14-bit bench is not the 6110E's
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("12 bits"), std::string::npos) << r.err;
  r = test::run_cli("measure --instrument 'sim?awg=rigol' --overwrite --out " +
                    (dir / "c.h5").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("awg=keysight or awg=tektronix"), std::string::npos) << r.err;
}

// Issue 41 item 4: one estimate everywhere. `impedance CAP.h5` with no option
// makes the pipeline's estimate (acq::default_estimate: its band, grid, record
// length, every dut shot averaged): a replay of the same capture (the seed's
// chain off, so no port-model refinement) reports the same resonances and
// anti-resonances to rounding, and the impedance command lists no feature
// outside the drive's band.
TEST(CliMeasure, ImpedanceAndReplayMakeTheSameEstimate) {
  const auto dir = tmp_dir() / "one-estimate";
  std::filesystem::create_directories(dir);
  const auto cap = (dir / "cap.h5").string();
  auto r = test::run_cli("measure --instrument sim --shots 3 --noise 0.01 --seed 41 --overwrite --out " +
                         cap);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = test::run_cli("impedance " + cap + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto imp = nlohmann::json::parse(r.out);
  const auto results = (dir / "r.h5").string(), jsonl = (dir / "r.jsonl").string();
  std::filesystem::remove(results);
  std::filesystem::remove(jsonl);
  r = test::run_cli("replay " + cap + " --out " + results + " --jsonl " + jsonl);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(jsonl);
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  const auto rep = nlohmann::json::parse(line)["result"];
  EXPECT_EQ(imp["samples_used"], 6000);
  ASSERT_GE(rep["resonances_hz"].size(), 2u);
  for (const char* key : {"resonances_hz", "antiresonances_hz"}) {
    ASSERT_EQ(imp["features"][key].size(), rep[key].size()) << key;
    for (std::size_t k = 0; k < rep[key].size(); ++k)
      EXPECT_NEAR(imp["features"][key][k].get<double>() / rep[key][k].get<double>(), 1.0, 1e-9) << key << " " << k;
  }
  ASSERT_TRUE(imp.contains("drive_band"));
  const double lo = imp["drive_band"]["lo_hz"], hi = imp["drive_band"]["hi_hz"];
  for (const char* kind : {"resonances", "antiresonances"}) {
    for (std::size_t k = 0; k < imp["features"][std::string(kind) + "_hz"].size(); ++k) {
      const double f = imp["features"][std::string(kind) + "_hz"][k];
      if (f < lo || f > hi) {
        EXPECT_FALSE(imp["features"][std::string(kind) + "_significant"][k].get<bool>());
      }
    }
  }
}
