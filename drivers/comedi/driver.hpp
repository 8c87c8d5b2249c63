#pragma once
// A DAQ board through Comedi (the reference bench's NI PCI-6110E under the
// kernel's ni_pcimio driver, or any board with a streaming analog input):
// two channels of the analog-input subdevice record v1 and v2, each on the
// smallest range of its table that holds ±range, with the reference of the
// address (differential by default); one streaming comedi_command per shot,
// started by an edge on a PFI line (the AWG's marker) or by software; raw
// values converted with the board's calibration: the soft-calibration
// polynomial where the subdevice is SDF_SOFT_CALIBRATED and a calibration
// file exists, else comedi_to_phys over the range table (hardware-calibrated
// boards such as the E series). A buffer overrun, no data before the
// timeout, the device going away, or the acquisition ending early are
// InstrumentErrors naming the device and what happened.
//
// Address: see drivers/comedi/address.hpp. Written from comedilib 0.11's
// header and manual; tested through the Board seam against the simulated
// board (drivers/sim/sim_comedi_board.*) only: it has never met a real
// board, nor the kernel's comedi_test driver.
#include <memory>
#include <optional>
#include <string>

#include "drivers/comedi/address.hpp"
#include "drivers/comedi/board.hpp"
#include "drivers/daq.hpp"

namespace piezo::drivers::comedi {

class Driver : public Daq {
 public:
  // Finds the analog-input subdevice and checks that it streams and has both
  // channels; throws InstrumentError naming the device otherwise.
  Driver(std::unique_ptr<Board> board, const Address& address);
  ~Driver() override;

  // "COMEDI,<board>,<device>,<driver>"
  std::string identity() const override;
  // The rate is what the board's timer can do (comedi_command_test rounds
  // the scan period; the record states the actual rate). A Comedi command
  // starts at its trigger, so no pretrigger samples; DC coupling only (the
  // driver sets none and the 6110E's default is DC).
  void configure(const DaqConfig& c) override;
  void arm() override;  // comedi_command: waits for the PFI edge (or runs now)
  DaqRecord fetch(double timeout_s) override;

  // How raw values become volts, per channel ("softcal polynomial" or
  // "comedi_to_phys over [-2, 2] V").
  std::string conversion(int ch) const;
  unsigned scan_period_ns() const { return cmd_.scan_period_ns; }

 private:
  struct Channel {
    unsigned channel = 0;
    unsigned range = 0;
    Range r;
    std::uint32_t maxdata = 0;
    std::optional<Polynomial> softcal;
  };
  std::string who() const;  // "comedi:///dev/comedi0 (pci-6110)"
  double to_volts(const Channel& ch, std::uint32_t raw) const;

  std::unique_ptr<Board> board_;
  Address address_;
  unsigned subdev_ = 0;
  SubdeviceInfo info_;
  Channel ch_[2];
  Command cmd_;
  bool configured_ = false;
  bool running_ = false;  // a command is running (cancelled before the next)
};

inline bool supports_address(const std::string& text) { return is_comedi_address(text); }

}  // namespace piezo::drivers::comedi
