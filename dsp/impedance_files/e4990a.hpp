#pragma once
// Keysight (Agilent) E4990A CSV ("Save Trace Data"), as the E4990A help shows it:
//   !Agilent Technologies,E4990A,MY521012345,A.02.10
//   !Date: Fri Apr 03 13:41:16 2015
//   BEGIN CH1_DATA
//   Title label, TEST DATA                          (when a title is on)
//   DCV(V), +5.230e-005, DCI(A), +2.335e-005        (when the DC monitors are on)
//   Frequency(Hz), |Z|(Ohm)-data, theta-z(deg)-data, theta-z(deg)-mem
//   +1.00000000000e+006, +1.97459864960e+002, +8.89119473020e+001, +8.89149657750e+001
//   END
//   BEGIN CH2_DATA ... END
// Each block is a table (table.hpp names its columns: |Z|/theta-z, R/X,
// Z-Real/Z-Imag, |Y|/theta-y, G/B, Y-Real/Y-Imag, Cp/D, Ls/Rs, ...; "-mem"
// columns are ignored). The first block that holds an impedance is read; the
// others are named in the notes. Decimal commas under comma separators (a
// comma-locale instrument: "+1,5e+006,+2,0e+002", twice the header's fields)
// are joined back; we know that layout only from a public reader that handles
// it, not from a file. Other Keysight instruments that write
// BEGIN/END blocks (ENA, PNA: "Freq(Hz), S11(REAL), S11(IMAG)") read the same way.
#include <istream>
#include <string>
#include <vector>

#include "dsp/impedance_files/imported_impedance.hpp"
#include "dsp/impedance_files/text.hpp"

namespace piezo::dsp {

ImportedImpedance read_e4990a_csv(std::istream& in, const std::string& name);

namespace zfiles {
ImportedImpedance read_e4990a_csv(const std::vector<TextLine>& lines, const std::string& name);
// "BEGIN CH1_DATA" (any channel number, any case).
bool e4990a_begin_line(std::string_view line);
}  // namespace zfiles

}  // namespace piezo::dsp
