// jobs::probe_bench — what the GUI's Connect button runs: the embedded simulated
// bench and the same simulated instruments served over TCP go through one test
// body (both must identify as the Keysight 33522B AWG and Infiniium DSO9104A
// DAQ); then the failures the instrument panel must tell apart: nobody at the
// address (TransportError), a bad address (invalid_argument).
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <memory>

#include "acquisition/sim_setup.hpp"
#include "drivers/scpi_client.hpp"
#include "drivers/sim/sim_awg.hpp"
#include "drivers/sim/sim_daq.hpp"
#include "drivers/sim/tcp_server.hpp"
#include "drivers/transport.hpp"
#include "jobs/bench_probe.hpp"

using namespace piezo;

namespace {
constexpr double kR1 = 3140.0;

// The two simulated instruments on free loopback ports, for the tcp:// case.
struct TcpBench {
  TcpBench() {
    auto bench = acq::make_sim_bench(acq::SimSpec{}, kR1);
    awg = std::make_unique<drivers::sim::TcpServer>(std::make_shared<drivers::sim::SimAwg>(bench),
                                                    "127.0.0.1", 0);
    daq = std::make_unique<drivers::sim::TcpServer>(std::make_shared<drivers::sim::SimDaq>(bench),
                                                    "127.0.0.1", 0);
    awg->start();
    daq->start();
  }
  std::unique_ptr<drivers::sim::TcpServer> awg, daq;
};

// A loopback port with nobody listening: bound, then released.
int closed_port() {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0) {
    ::close(fd);
    return -1;
  }
  ::close(fd);
  return ntohs(a.sin_port);
}

class BenchProbe : public ::testing::TestWithParam<const char*> {};
}  // namespace

TEST_P(BenchProbe, IdentifiesBothInstruments) {
  std::unique_ptr<TcpBench> tcp;
  std::string awg = "sim", daq;
  if (std::string(GetParam()) == "tcp") {
    tcp = std::make_unique<TcpBench>();
    awg = "tcp://127.0.0.1:" + std::to_string(tcp->awg->port());
    daq = "tcp://127.0.0.1:" + std::to_string(tcp->daq->port());
  }
  const jobs::BenchProbe p = jobs::probe_bench(awg, daq, acq::SimSpec{}, kR1);
  EXPECT_NE(p.awg_idn.find("33522B"), std::string::npos) << p.awg_idn;
  EXPECT_NE(p.daq_idn.find("DSO9104A"), std::string::npos) << p.daq_idn;
  EXPECT_FALSE(p.description.empty());
}

INSTANTIATE_TEST_SUITE_P(Transports, BenchProbe, ::testing::Values("sim", "tcp"));

TEST(BenchProbeErrors, NobodyAtTheAddressIsATransportError) {
  const int port = closed_port();
  ASSERT_GT(port, 0);
  const std::string addr = "tcp://127.0.0.1:" + std::to_string(port);
  try {
    jobs::probe_bench(addr, "", acq::SimSpec{}, kR1);
    FAIL() << "no exception";
  } catch (const drivers::TransportError& e) {
    EXPECT_NE(std::string(e.what()).find(addr), std::string::npos) << e.what();
  }
}

TEST(BenchProbeErrors, BadAddressesAreInvalidArguments) {
  EXPECT_THROW(jobs::probe_bench("gpib://3", "", acq::SimSpec{}, kR1), std::invalid_argument);
  // A USB bench cannot guess the DAQ's address.
  EXPECT_THROW(jobs::probe_bench("usbtmc://0957:1607", "", acq::SimSpec{}, kR1),
               std::invalid_argument);
}
