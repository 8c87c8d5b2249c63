#pragma once
// The driver registry (after libsigrok's driver list): a string-keyed factory
// per role. register_builtin_drivers() is the one place that lists the
// drivers compiled in; open_awg()/open_daq() ask the instrument's *IDN? and
// open the driver whose model table accepts the reply, so one address works
// whatever the make of the instrument behind it. An instrument that is both
// the AWG and the DAQ (the Red Pitaya) has a dual-role entry: one address,
// one connection, both roles.
#include <functional>
#include <memory>
#include <utility>
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

// Both roles of one instrument (one connection shared by the two).
struct InstrumentRoles {
  std::unique_ptr<Awg> awg;  // null if the instrument is not a generator
  std::unique_ptr<Daq> daq;  // null if it is not a digitizer
};

struct DualRoleEntry {
  std::string key;          // "redpitaya"
  std::string description;  // "Red Pitaya STEMlab 125-14 (generator and acquisition)"
  std::function<bool(const std::string& idn)> accepts;
  std::function<InstrumentRoles(std::unique_ptr<Transport>)> open;  // both set
};

// A DAQ opened from an address of its own rather than over a Transport and
// *IDN? (a board inside the PC, through a kernel interface such as Comedi).
struct BoardDaqEntry {
  std::string key;           // "comedi"
  std::string description;   // "DAQ boards through Comedi (NI PCI-6110E, ...)"
  std::string address_form;  // "comedi:///dev/comediN?trigger=pfiN&..."
  std::function<bool(const std::string& address)> accepts;
  std::function<std::unique_ptr<Daq>(const std::string& address)> open;
};

class DriverRegistry {
 public:
  // Throws std::invalid_argument on an empty or duplicate key, or a missing function.
  void add_awg(DriverEntry<Awg> e);
  void add_daq(DriverEntry<Daq> e);
  void add_dual(DualRoleEntry e);
  void add_board_daq(BoardDaqEntry e);
  const std::vector<BoardDaqEntry>& board_daqs() const { return boards_; }
  // The board DAQ whose entry accepts the address, opened; nullptr if none accepts it.
  std::unique_ptr<Daq> open_board_daq(const std::string& address) const;
  // How to run a family against its simulated twin, for listings ("" if it has none).
  // Throws std::invalid_argument for a key no entry has.
  void set_simulated_twin(const std::string& key, std::string how);
  std::string simulated_twin(const std::string& key) const;
  // What a front end fills in to use a family (the GUI's "Use"): the AWG and
  // the DAQ address ("" leaves that field as it is) — an in-process twin's
  // address, or a board's default one. Throws std::invalid_argument for a key no entry has.
  void set_use_addresses(const std::string& key, std::string awg, std::string daq);
  std::pair<std::string, std::string> use_addresses(const std::string& key) const;
  const std::vector<DriverEntry<Awg>>& awgs() const { return awgs_; }
  const std::vector<DriverEntry<Daq>>& daqs() const { return daqs_; }
  const std::vector<DualRoleEntry>& duals() const { return duals_; }

  // Asks *IDN? and opens the first driver that accepts the reply (the
  // role's own entries first, then the dual-role ones, of which only that
  // role is kept); throws InstrumentError naming the reply and the known
  // drivers if none does.
  std::unique_ptr<Awg> open_awg(std::unique_ptr<Transport> t) const;
  std::unique_ptr<Daq> open_daq(std::unique_ptr<Transport> t) const;
  // Asks *IDN? once and opens whatever the instrument is: both roles for a
  // dual-role entry, else the AWG, else the DAQ that accepts the reply.
  InstrumentRoles open_instrument(std::unique_ptr<Transport> t) const;
  // The driver of that key (no *IDN? match needed); throws std::invalid_argument for an unknown
  // key.
  std::unique_ptr<Awg> open_awg(const std::string& key, std::unique_ptr<Transport> t) const;

 private:
  std::vector<DriverEntry<Awg>> awgs_;
  std::vector<DriverEntry<Daq>> daqs_;
  std::vector<DualRoleEntry> duals_;
  std::vector<BoardDaqEntry> boards_;
  struct Extra {
    std::string key, twin, awg_address, daq_address;
  };
  std::vector<Extra> extras_;  // per key: the twin, the addresses to use it
  Extra& extra(const std::string& key);
  bool has_key(const std::string& key) const;
};

// AWGs: keysight33500, tektronix_awg. DAQs: infiniium; by address: comedi. Both: redpitaya.
void register_builtin_drivers(DriverRegistry& r);

// One family as the CLI (`piezobench instruments`) and the GUI list it.
struct DriverFamily {
  std::string key, description;
  std::vector<std::string> roles;  // "awg", "daq"
  std::string chosen_by;           // "*IDN?" (any SCPI address) or "address"
  std::string address_form;        // for chosen_by == "address"
  std::string simulated_twin;      // how to run it against its twin ("" if none)
  std::string awg_address, daq_address;  // what a front end fills in to use it ("": unchanged)
};
// In registration order: AWGs, DAQs, dual-role instruments, board DAQs.
std::vector<DriverFamily> list_families(const DriverRegistry& r);

// The docs' table of the families (drivers/README.md, "The registered
// families"; tests/drivers/test_driver_registry.cpp compares the two).
std::string family_table_markdown(const DriverRegistry& r);

// The registry filled by register_builtin_drivers() (built once, never changed).
const DriverRegistry& builtin_drivers();

// *IDN? over a bare transport: one reply line, terminator stripped. Throws
// TransportError (timeout, closed) or InstrumentError (empty, overlong, or
// followed by unexpected bytes).
std::string query_idn(Transport& t);

}  // namespace piezo::drivers
