// The jobs' room (jobs/measure/): `piezobench sim-instrument` (see sim_instrument_job.hpp).
#include "jobs/measure/sim_instrument_job.hpp"

#include <chrono>
#include <memory>
#include <stdexcept>
#include <thread>
#include <vector>

#include "drivers/sim/sim_awg.hpp"
#include "drivers/sim/sim_daq.hpp"
#include "drivers/sim/sim_redpitaya.hpp"
#include "drivers/sim/sim_tektronix_awg.hpp"
#include "drivers/sim/tcp_server.hpp"
#include "jobs/job_error.hpp"

namespace piezo::jobs {

void run_sim_instrument(const SimInstrumentRequest& req, const SimInstrumentCallbacks& cb) {
  if (req.port < 1 || req.port > 65534) throw InputError("--port must be 1..65534");
  const acq::SimSpec spec = sim_spec(req.sim, model::TubeGeometry{});
  if (spec.disturbances.drift_rel != 0.0 && cb.note)  // a SCPI session does not tell the bench its capture
    cb.note("drift needs the capture's shot count, which a client over "
            "SCPI does not send: no drift is applied (step counts the acquisitions)");
  auto bench = acq::make_sim_bench(spec, req.r1);
  const auto port = static_cast<std::uint16_t>(req.port);
  std::vector<std::unique_ptr<drivers::sim::TcpServer>> servers;
  // A port in use or a host that is not an address: the user's to fix (exit 2), with the next step.
  auto serve = [&](std::shared_ptr<drivers::sim::ScpiDevice> dev, std::uint16_t p) {
    try {
      servers.push_back(std::make_unique<drivers::sim::TcpServer>(std::move(dev), req.host, p));
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      if (what.find("cannot listen") != std::string::npos)
        throw InputError(what + ". Another program (another sim-instrument?) may hold the port: choose another "
                                "--port (the DAQ takes PORT+1 too), or stop that program");
      if (what.find("not an IPv4 address") != std::string::npos)
        throw InputError(what + ": give --host as a dotted IPv4 address, e.g. 127.0.0.1 or 0.0.0.0");
      throw;
    }
  };
  SimInstrumentListening at;
  if (req.dialect == "redpitaya") {  // one instrument, both roles, one port
    std::shared_ptr<drivers::sim::ScpiDevice> dev;
    try {
      dev = std::make_shared<drivers::sim::SimRedPitaya>(bench);
    } catch (const std::invalid_argument& e) {
      throw InputError(std::string(e.what()) + " (--adc-bits)");
    }
    serve(dev, port);
    servers.back()->start();
    at = {true, servers[0]->port(), servers[0]->port(), "Red Pitaya STEMlab 125-14"};
  } else {
    const bool tek = req.dialect == "tektronix";
    std::shared_ptr<drivers::sim::ScpiDevice> awg_dev;
    if (tek) awg_dev = std::make_shared<drivers::sim::SimTektronixAwg>(bench);
    else awg_dev = std::make_shared<drivers::sim::SimAwg>(bench);
    serve(awg_dev, port);
    serve(std::make_shared<drivers::sim::SimDaq>(bench), static_cast<std::uint16_t>(port + 1));
    for (auto& srv : servers) srv->start();
    at = {false, servers[0]->port(), servers[1]->port(), tek ? "Tektronix AWG5014C" : "Keysight 33522B"};
  }
  if (cb.listening) cb.listening(at);
  const auto t0 = std::chrono::steady_clock::now();
  while (!(cb.cancel && *cb.cancel)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (req.seconds > 0 && std::chrono::steady_clock::now() - t0 > std::chrono::duration<double>(req.seconds)) break;
  }
}

}  // namespace piezo::jobs
