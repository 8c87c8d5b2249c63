#pragma once
// Touchstone one-port files (.s1p, .ts) and two-port S-parameter files (.s2p),
// versions 1.x and 2.0 (IBIS Touchstone specification 2.0, 2009):
//   option line  "# <Hz|kHz|MHz|GHz> <S|Z|Y> <RI|MA|DB> R <z0>", any order,
//                defaults GHz S MA R 50; only the first counts
//   comments     '!' to the end of any line
//   v2.0         [Version] 2.0, [Number of Ports] 1, [Number of Frequencies] n
//                (checked), [Reference] z0 (same or next line; for S only),
//                [Begin Information] ... [End Information] (skipped),
//                [Matrix Format], [Network Data], [End]; a point may span lines
//   values       S11 -> Z = z0 (1 + S)/(1 − S); Z and Y are normalized to R in
//                1.x (Z = value·R, Y = value/R) and in ohm / siemens in 2.0
//   two ports    [Number of Ports] 2, a ".s2p" name, or 9 values on the first
//                1.x data line (not named .s1p): S11 S21 S12 S22 per line
//                (2.0: [Two-Port Data Order] 12_21 or 21_12). A transmission
//                export: the device sits in series between the ports (the
//                series-through fixture crystals and thin-film resonators are
//                measured in), Z = 2·z0·(1 − S21)/S21 from S21, never S11 as
//                a reflection; unless S21 is at noise level (median |S21|
//                below −60 dB: nothing passes), when the device is on port 1
//                and S11 is read as a reflection, or the two-port is not one
//                series element (median |S11 + S21 − 1| above 0.1, where a
//                series element has 0: a filter, shunt paths), when S11 is
//                read as port 1's input impedance with port 2 terminated
//                (a LibreVNA .s2p of a SAW filter: 1.58; the N5230A's MEMS
//                resonator: 0.003). A note says which.
//                (Seen in a real file: an Agilent N5230A PNA-L .s2p, 1.x RI.)
// Refused, with the reason: more than two ports, two-port Z/Y, G/H
// parameters, mixed-mode and noise data, a count that disagrees with
// [Number of Frequencies].
#include <istream>
#include <string>
#include <vector>

#include "dsp/impedance_files/imported_impedance.hpp"
#include "dsp/impedance_files/text.hpp"

namespace piezo::dsp {

ImportedImpedance read_touchstone(std::istream& in, const std::string& name);

namespace zfiles {
ImportedImpedance read_touchstone(const std::vector<TextLine>& lines, const std::string& name);
// True when the tokens after '#' are all option-line tokens.
bool touchstone_option_line(std::string_view line);
}  // namespace zfiles

}  // namespace piezo::dsp
