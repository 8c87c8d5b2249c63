#pragma once
// The address of a DAQ board through Comedi, as --daq spells it:
//   comedi:///dev/comedi0?trigger=pfi0&aref=diff&channels=0,1&edge=rising
//   comedi-sim:///dev/comedi0?...   the same, on the simulated board (a
//                                   PCI-6110 twin fed by the embedded bench)
// Options (all optional; defaults in brackets):
//   trigger   pfiN (start on an edge of PFI line N: the AWG's marker) or
//             software (start when armed)                       [pfi0]
//   edge      rising | falling (of the PFI trigger)             [rising]
//   aref      diff | rse | nrse (differential, referenced or
//             non-referenced single-ended)                      [diff]
//   channels  C1,C2: the board's channels recording v1 and v2   [0,1]
//   softcal   1 (comedi-sim only): the simulated board reports
//             SDF_SOFT_CALIBRATED with an ideal polynomial, whose
//             volts are the embedded bench's exactly           [0]
#include <string>
#include <string_view>

#include "drivers/comedi/board.hpp"

namespace piezo::drivers::comedi {

struct Address {
  bool simulated = false;  // comedi-sim://
  std::string device = "/dev/comedi0";
  bool external_trigger = true;
  unsigned pfi = 0;
  bool falling = false;
  Aref aref = Aref::Diff;
  unsigned channels[2] = {0, 1};
  bool sim_softcal = false;  // comedi-sim: soft-calibrated board

  std::string to_string() const;
};

bool is_comedi_address(std::string_view text);  // comedi:// or comedi-sim://
// Throws std::invalid_argument naming the address and the problem.
Address parse_address(std::string_view text);

}  // namespace piezo::drivers::comedi
