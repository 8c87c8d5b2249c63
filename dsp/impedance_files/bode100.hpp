#pragma once
// OMICRON Lab Bode 100 CSV, as the Bode Analyzer Suite exports it: one header
// line "Frequency (Hz);Trace 1: Impedance: Real (Ω);Trace 1: Impedance:
// Imaginary (Ω);...", then one row per frequency; UTF-8 with a byte-order
// mark, CR LF, ';' between values (the layout of the one export we could
// see: github.com/ladmanj/bode2spice, data_example/example.csv). Read by the table reader
// (table.hpp), so the variants we could not see in a real file are accepted
// too: Magnitude (Ω) / Phase (°), Magnitude (dB), admittance, ',' or tab
// separators, decimal commas, Ω written as U+2126 or U+03A9, ° in Latin-1.
// Gain columns are not an impedance (the error names them); Reflection
// columns read as S11 with z0 = 50 ohm assumed (a note says so).
#include <istream>
#include <string>
#include <vector>

#include "dsp/impedance_files/imported_impedance.hpp"
#include "dsp/impedance_files/text.hpp"

namespace piezo::dsp {

ImportedImpedance read_bode100_csv(std::istream& in, const std::string& name);

namespace zfiles {
ImportedImpedance read_bode100_csv(const std::vector<TextLine>& lines, const std::string& name);
// A header of the Bode Analyzer Suite: "Frequency ..." followed by "Trace <n>:" columns.
bool bode100_header(std::string_view line);
}  // namespace zfiles

}  // namespace piezo::dsp
