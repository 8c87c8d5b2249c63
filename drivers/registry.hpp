#pragma once
// The driver registry (after libsigrok's driver list): a string-keyed factory
// per role. register_builtin_drivers() is the one place that lists the
// drivers compiled in; open_awg()/open_daq() ask the instrument's *IDN? and
// open the driver whose model table accepts the reply, so one address works
// whatever the make of the instrument behind it.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "drivers/awg.hpp"
#include "drivers/daq.hpp"
#include "drivers/transport.hpp"

namespace piezo::drivers {

template <class Role>
struct DriverEntry {
  std::string key;          // "tektronix_awg"
  std::string description;  // "Tektronix AWG5000/AWG7000"
  std::function<bool(const std::string& idn)> accepts;
  std::function<std::unique_ptr<Role>(std::unique_ptr<Transport>)> open;
};

class DriverRegistry {
 public:
  // Throws std::invalid_argument on an empty or duplicate key, or a missing function.
  void add_awg(DriverEntry<Awg> e);
  void add_daq(DriverEntry<Daq> e);
  const std::vector<DriverEntry<Awg>>& awgs() const { return awgs_; }
  const std::vector<DriverEntry<Daq>>& daqs() const { return daqs_; }

  // Asks *IDN? and opens the first driver that accepts the reply; throws
  // InstrumentError naming the reply and the known drivers if none does.
  std::unique_ptr<Awg> open_awg(std::unique_ptr<Transport> t) const;
  std::unique_ptr<Daq> open_daq(std::unique_ptr<Transport> t) const;
  // The driver of that key (no *IDN? match needed); throws std::invalid_argument for an unknown
  // key.
  std::unique_ptr<Awg> open_awg(const std::string& key, std::unique_ptr<Transport> t) const;

 private:
  std::vector<DriverEntry<Awg>> awgs_;
  std::vector<DriverEntry<Daq>> daqs_;
};

// AWGs: keysight33500, tektronix_awg. DAQs: infiniium.
void register_builtin_drivers(DriverRegistry& r);

// The registry filled by register_builtin_drivers() (built once, never changed).
const DriverRegistry& builtin_drivers();

// *IDN? over a bare transport: one reply line, terminator stripped. Throws
// TransportError (timeout, closed) or InstrumentError (empty, overlong, or
// followed by unexpected bytes).
std::string query_idn(Transport& t);

}  // namespace piezo::drivers
