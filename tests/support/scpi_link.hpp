#pragma once
// Driver tests' plumbing: one simulated instrument behind a transport of the
// kind under test ("loopback" in process, or "tcp" to a local server), an RC
// bench with seeded DAQ noise, and a seeded drive waveform.
#include <chrono>
#include <cmath>
#include <memory>
#include <random>
#include <string>

#include "drivers/awg.hpp"
#include "drivers/sim/loopback_transport.hpp"
#include "drivers/sim/sim_bench.hpp"
#include "drivers/sim/tcp_server.hpp"
#include "drivers/tcp_transport.hpp"
#include "tests/support/rc_physics.hpp"

namespace piezo::test {

// The server (TCP) outlives the transport, which the driver owns.
struct ScpiLink {
  std::unique_ptr<drivers::sim::TcpServer> server;
  std::unique_ptr<drivers::Transport> transport;
};

// A short reply timeout: the timeout cases wait it out once.
inline ScpiLink connect_link(const std::string& kind, std::shared_ptr<drivers::sim::ScpiDevice> dev,
                             const std::string& loop_name) {
  ScpiLink l;
  if (kind == "loopback") {
    l.transport = std::make_unique<drivers::sim::LoopbackTransport>(std::move(dev), loop_name);
  } else {
    l.server = std::make_unique<drivers::sim::TcpServer>(std::move(dev), "127.0.0.1", 0);
    l.server->start();
    l.transport = std::make_unique<drivers::TcpTransport>("127.0.0.1", l.server->port(),
                                                          std::chrono::milliseconds(400));
  }
  return l;
}

// R1 and C of the RC stand-in transducer; seeded noise, so that sample-for-sample
// equality of two paths also checks that their RNGs stay in step.
inline std::shared_ptr<drivers::sim::SimBench> rc_bench(std::uint64_t seed, double noise, double r1,
                                                        double c) {
  drivers::sim::DaqImperfections imp;
  imp.noise_rel[0] = imp.noise_rel[1] = noise;
  return std::make_shared<drivers::sim::SimBench>(std::make_unique<RcPhysics>(r1, c), imp, seed);
}

// A noise burst normalised to peak 1 (every float32 bit pattern matters).
inline drivers::ArbWaveform seeded_waveform(std::uint64_t seed, std::size_t n, double rate_hz,
                                            double peak_v) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  drivers::ArbWaveform w;
  w.samples.resize(n);
  double peak = 0;
  for (auto& x : w.samples) peak = std::max(peak, std::fabs(x = g(rng)));
  for (auto& x : w.samples) x /= peak;
  w.sample_rate_hz = rate_hz;
  w.peak_v = peak_v;
  return w;
}

}  // namespace piezo::test
