#pragma once
// Any delimited table of an impedance sweep with a header line: a frequency
// column and a pair of columns of Z, Y or S11 (columns.hpp names them), read
// whatever the tool that wrote it:
//   separators  ',' ';' tab or blanks (found from the header and first row);
//               decimal commas with ';', tab or blank separators, and the
//               "+1,5e+006,+2,0e+002" of a comma-locale instrument (every
//               field split in two: twice the header's columns)
//   lines       blank lines, and rows whose columns read are empty (",,,": a
//               padded file, side-by-side sweeps of different lengths),
//               anywhere; '#' and '!' comments; text before the
//               header (titles, settings) skipped with a note; a header in the
//               last comment line before the data ("! Stimulus(Hz), ...") when
//               there is no other; no header at all: f_hz, re_ohm, im_ohm
//               (three columns only; any other count: name them, --columns)
//   columns     the first usable pair, in this order: Z real/imaginary,
//               |Z|/phase (linear or dB), Y real/imaginary, |Y|/phase, S21
//               (transmission: series-through Z, preferred to S11 unless S21
//               is at noise level or S11 + S21 is not 1), S11,
//               series Ls/Cs with Rs/D/Q, parallel Cp/Lp with G/Rp/D/Q; then
//               any two parameters lcr_parameters.hpp turns into Z (|Z| and
//               X, θ and R, X and D, ...) or |Z| alone (magnitude only); the
//               uncertainty band of dsp/impedance_io (abs_sigma_ohm,
//               phase_sigma_deg, coverage_factor) when present
// Errors name the file, the line, what was found and the next step:
//   "x.csv: line 1: no frequency column among [Freq2, Foo, Bar]; name the columns ..."
//   "x.csv: line 12: 2 columns, the header has 3"
#include <istream>
#include <string>
#include <vector>

#include "dsp/impedance_files/imported_impedance.hpp"
#include "dsp/impedance_files/text.hpp"

namespace piezo::dsp {

ImportedImpedance read_impedance_table(std::istream& in, const std::string& name);

namespace zfiles {

struct TableOptions {
  const char* fn = "read_impedance_table";  // the reader (kept out of messages)
  ImpedanceFileFormat format = ImpedanceFileFormat::Table;
  std::string format_name = "table";
  bool allow_headerless = true;
  // The columns' names given instead of the file's header (`--columns`, or a
  // reader that translated an instrument's names): every text line above the
  // data is skipped; a row may lack trailing columns named "-" (skipped).
  std::vector<std::string> columns;
  // What the names above are called in messages and notes (the instrument's
  // own names); empty: the names themselves.
  std::vector<std::string> labels;
  std::string columns_origin = "--columns";  // "names N" in messages
  int header_line = 0;  // the instrument's header line of the names above (0: none)
};

// Appended to a message about columns we could not read: how to name them.
extern const char* const kColumnsHint;

// The table reader on lines already split (the E4990A reader hands it one
// BEGIN ... END block, the Bode 100 reader the whole file).
ImportedImpedance read_table(const std::vector<TextLine>& lines, const std::string& name,
                             const TableOptions& opt);

}  // namespace zfiles
}  // namespace piezo::dsp
