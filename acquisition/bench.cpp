#include "acquisition/bench.hpp"

#include "drivers/comedi/address.hpp"
#include "drivers/comedi/driver.hpp"
#include "drivers/instrument_uri.hpp"
#include "drivers/registry.hpp"
#include "drivers/scpi_client.hpp"
#include "drivers/sim/loopback_transport.hpp"
#include "drivers/sim/sim_awg.hpp"
#include "drivers/sim/sim_comedi_board.hpp"
#include "drivers/sim/sim_daq.hpp"
#include "drivers/sim/sim_tektronix_awg.hpp"
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

namespace {
// A DAQ board through Comedi (--daq comedi://... or, on the embedded
// simulated bench only, comedi-sim://...: the simulated PCI-6110).
std::unique_ptr<Daq> open_comedi(const std::string& address,
                                 const std::shared_ptr<sim::SimBench>& sim_bench) {
  const auto a = comedi::parse_address(address);
  if (a.simulated) {
    if (!sim_bench)
      throw std::invalid_argument(
          "DAQ address '" + address +
          "': the simulated Comedi board belongs to the embedded simulated bench "
          "(--instrument sim or sim?awg=tektronix)");
    return std::make_unique<comedi::Driver>(
        std::make_unique<sim::SimComediBoard>(sim_bench, a.device, a.sim_softcal), a);
  }
  return builtin_drivers().open_board_daq(address);  // comedi:// (drivers/registry.cpp)
}
}  // namespace

Bench open_bench(const BenchAddress& addr, std::shared_ptr<sim::SimBench> sim_bench) {
  Bench b;
  auto awg_uri = parse_instrument_uri(addr.awg);
  if (awg_uri.kind == InstrumentUri::Kind::Sim) {
    if (!sim_bench) throw std::invalid_argument("open_bench: the simulated bench needs its physics");
    std::shared_ptr<sim::ScpiDevice> awg_dev;
    if (awg_uri.sim_awg == "tektronix")
      awg_dev = std::make_shared<sim::SimTektronixAwg>(sim_bench);
    else
      awg_dev = std::make_shared<sim::SimAwg>(sim_bench);
    b.awg = builtin_drivers().open_awg(std::make_unique<sim::LoopbackTransport>(awg_dev, "sim://awg"));
    std::string daq_name = "sim://daq";
    if (addr.daq && comedi::is_comedi_address(*addr.daq)) {
      b.daq = open_comedi(*addr.daq, sim_bench);
      daq_name = *addr.daq;
    } else if (addr.daq && *addr.daq != "sim") {
      throw std::invalid_argument(
          "DAQ address '" + *addr.daq +
          "': the embedded simulated bench's DAQ is its own twin (sim) or the "
          "simulated Comedi board (comedi-sim:///dev/comediN)");
    } else {
      auto daq_dev = std::make_shared<sim::SimDaq>(sim_bench);
      b.daq = builtin_drivers().open_daq(
          std::make_unique<sim::LoopbackTransport>(daq_dev, "sim://daq"));
    }
    b.sim = sim_bench;
    b.description = "embedded simulated bench (" + sim_bench->physics().description() + ")";
    if (awg_uri.sim_awg != "keysight" || daq_name != "sim://daq")
      b.description +=
          ": AWG [" + b.awg->identity() + "], DAQ " + daq_name + " [" + b.daq->identity() + "]";
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
  if (comedi::is_comedi_address(daq_addr))
    b.daq = open_comedi(daq_addr, nullptr);
  else
    b.daq = builtin_drivers().open_daq(open_transport(daq_addr));
  b.description = "AWG " + addr.awg + " [" + b.awg->identity() + "], DAQ " + daq_addr + " [" +
                  b.daq->identity() + "]";
  return b;
}

}  // namespace piezo::acq
