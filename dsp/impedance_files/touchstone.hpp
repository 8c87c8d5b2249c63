#pragma once
// Touchstone one-port files (.s1p, .ts), versions 1.x and 2.0 (IBIS Touchstone
// specification 2.0, 2009):
//   option line  "# <Hz|kHz|MHz|GHz> <S|Z|Y> <RI|MA|DB> R <z0>", any order,
//                defaults GHz S MA R 50; only the first counts
//   comments     '!' to the end of any line
//   v2.0         [Version] 2.0, [Number of Ports] 1, [Number of Frequencies] n
//                (checked), [Reference] z0 (same or next line; for S only),
//                [Begin Information] ... [End Information] (skipped),
//                [Matrix Format], [Network Data], [End]; a point may span lines
//   values       S11 -> Z = z0 (1 + S)/(1 − S); Z and Y are normalized to R in
//                1.x (Z = value·R, Y = value/R) and in ohm / siemens in 2.0
// Refused, with the reason: more than one port, G/H parameters, mixed-mode
// and noise data, a count that disagrees with [Number of Frequencies].
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
