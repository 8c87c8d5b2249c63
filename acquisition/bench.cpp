#include "acquisition/bench.hpp"

#include "drivers/instrument_uri.hpp"
#include "drivers/registry.hpp"
#include "drivers/scpi_client.hpp"
#include "drivers/sim/loopback_transport.hpp"
#include "drivers/sim/sim_awg.hpp"
#include "drivers/sim/sim_daq.hpp"
#include "drivers/tcp_transport.hpp"
#include "drivers/usbtmc/usbtmc_transport.hpp"

namespace piezo::acq {

using namespace piezo::drivers;

std::unique_ptr<Transport> open_transport(const std::string& address) {
  auto uri = parse_instrument_uri(address);
  switch (uri.kind) {
    case InstrumentUri::Kind::Tcp:
      return std::make_unique<TcpTransport>(uri.host, uri.port);
    case InstrumentUri::Kind::UsbTmc:
      return open_usbtmc(uri);
    case InstrumentUri::Kind::Sim:
      break;
  }
  throw std::invalid_argument("open_transport: 'sim' has no transport of its own");
}

Bench open_bench(const BenchAddress& addr, std::shared_ptr<sim::SimBench> sim_bench) {
  Bench b;
  auto awg_uri = parse_instrument_uri(addr.awg);
  if (awg_uri.kind == InstrumentUri::Kind::Sim) {
    if (!sim_bench) throw std::invalid_argument("open_bench: the simulated bench needs its physics");
    auto awg_dev = std::make_shared<sim::SimAwg>(sim_bench);
    auto daq_dev = std::make_shared<sim::SimDaq>(sim_bench);
    b.awg = builtin_drivers().open_awg(std::make_unique<sim::LoopbackTransport>(awg_dev, "sim://awg"));
    b.daq = builtin_drivers().open_daq(std::make_unique<sim::LoopbackTransport>(daq_dev, "sim://daq"));
    b.sim = sim_bench;
    b.description = "embedded simulated bench (" + sim_bench->physics().description() + ")";
    return b;
  }
  // The driver is chosen from each instrument's *IDN? reply (drivers/registry.hpp).
  // The first address may be an instrument with both roles (a Red Pitaya):
  // then, without --daq, it is the whole bench.
  const bool tcp = awg_uri.kind == InstrumentUri::Kind::Tcp;
  if (!addr.daq && !tcp)
    throw std::invalid_argument("instrument address '" + addr.awg +
                                "': a USBTMC bench needs the DAQ's address too (--daq)");
  auto first = builtin_drivers().open_instrument(open_transport(addr.awg));
  if (!first.awg)
    throw InstrumentError(addr.awg + ": '" + first.daq->identity() +
                          "' is a digitizer, not a generator; give the AWG's address to --instrument");
  b.awg = std::move(first.awg);
  if (first.daq && !addr.daq) {
    b.daq = std::move(first.daq);
    b.description = "AWG and DAQ " + addr.awg + " [" + b.awg->identity() + "] (one instrument, both roles)";
    return b;
  }
  const std::string daq_addr =
      addr.daq ? *addr.daq : "tcp://" + awg_uri.host + ":" + std::to_string(awg_uri.port + 1);
  // An explicit --daq wins over a dual-role instrument's own acquisition.
  b.daq = builtin_drivers().open_daq(open_transport(daq_addr));
  b.description = "AWG " + addr.awg + " [" + b.awg->identity() + "], DAQ " + daq_addr + " [" +
                  b.daq->identity() + "]";
  return b;
}

}  // namespace piezo::acq
