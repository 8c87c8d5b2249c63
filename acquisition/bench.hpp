#pragma once
// Opens the bench's two instruments from their addresses: the embedded
// simulated bench ("sim"), SCPI over TCP, or USBTMC. The simulated bench is
// an ordinary pair of drivers: the same keysight33500 / infiniium drivers
// talk to simulated instruments through an in-process loopback transport.
// Each driver is chosen from its instrument's *IDN? reply through the
// driver registry (drivers/registry.hpp), so a Tektronix AWG5000/7000 (or
// its simulated twin, `sim-instrument --dialect tektronix`) works at any address.
// An instrument with both roles (a Red Pitaya STEMlab 125-14, or its twin,
// `sim-instrument --dialect redpitaya`) is the whole bench at one address
// when no --daq is given.
#include <memory>
#include <optional>
#include <string>

#include "drivers/awg.hpp"
#include "drivers/daq.hpp"
#include "drivers/sim/sim_bench.hpp"
#include "drivers/transport.hpp"

namespace piezo::acq {

struct BenchAddress {
  std::string awg = "sim";  // sim | tcp://HOST:PORT | usbtmc://VID:PID[/SERIAL]
  // default: the AWG's own acquisition if it has one (Red Pitaya), else tcp →
  // PORT+1 on the same host; sim → sim
  std::optional<std::string> daq;
};

struct Bench {
  std::unique_ptr<drivers::Awg> awg;
  std::unique_ptr<drivers::Daq> daq;
  std::shared_ptr<drivers::sim::SimBench> sim;  // set for the embedded simulated bench
  std::string description;
};

// For "sim", `sim_bench` must be given (its physics decides what is measured).
Bench open_bench(const BenchAddress& addr, std::shared_ptr<drivers::sim::SimBench> sim_bench = nullptr);

// A transport for one address (tcp / usbtmc); throws std::invalid_argument or TransportError.
std::unique_ptr<drivers::Transport> open_transport(const std::string& address);

}  // namespace piezo::acq
