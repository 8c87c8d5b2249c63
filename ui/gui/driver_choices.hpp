#pragma once
// The instrument window's driver combo box: one entry per family of the
// driver registry (drivers/registry.hpp), with what the window shows for it
// and what "Use" puts in the address fields. Window-free, so tests/gui's
// unit test reads it without a display.
#include <string>
#include <vector>

namespace piezo::gui {

struct DriverChoice {
  std::string key;
  std::string label;  // "comedi [daq]: DAQ boards through Comedi (...)"
  std::string how;    // how it is chosen, and its address form
  std::string twin;   // how to run it against its simulated twin ("" if none)
  // What "Use" fills in: the AWG field (empty: unchanged) and the DAQ field
  // (empty: unchanged). *IDN?-chosen families take any address, so they fill
  // the simulated twin where one runs in process; board DAQs their address.
  std::string awg_address, daq_address;
};

std::vector<DriverChoice> driver_choices();

}  // namespace piezo::gui
