#pragma once
// One entry point for every impedance file a bench engineer brings: the format
// is found from the content, the file name's extension deciding only where the
// content alone does not (numbers without any header, or a '#' line that is
// not a valid option line: Touchstone for .s1p, .ts and .snp, a table otherwise).
//   Touchstone  first meaningful line "[Version] 2.0" or an option line "# ..."
//   4294A       a "TRACE: A" line, or a first line "4294A ..."
//   E4990A      a "BEGIN CHn_DATA" line
//   Bode 100    a first line "Frequency ...;Trace 1: ..."
//   HIOKI       a header line "No.","FREQUENCY(Hz)",... (hioki.hpp)
//   LabOne      columns realz/imagz/absz/phasez/param0, or chunk and timestamp,
//               or a '%' comment naming LabOne (labone.hpp)
//   table       everything else (table.hpp)
// A hint other than Auto skips the detection and runs that reader; columns
// (`--columns f[kHz],G[uS],B[uS]`) skip it too and read a table with those
// names instead of its header (columns.hpp's parse_column_spec).
// Errors: std::invalid_argument naming the file, the line, what was found and,
// where it helps, the next step (no function names: the message is the
// user's); read_impedance_file throws std::runtime_error when it cannot open.
#include <istream>
#include <string>
#include <string_view>

#include "dsp/impedance_files/imported_impedance.hpp"

namespace piezo::dsp {

ImpedanceFileFormat detect_impedance_format(std::string_view text, const std::string& name);

struct ImpedanceReadOptions {
  ImpedanceFileFormat hint = ImpedanceFileFormat::Auto;
  std::string columns;  // a table's column names, "f[kHz],G[uS],B[uS]"; empty: the file's
};

ImportedImpedance read_impedance_any(std::istream& in, const std::string& name,
                                     ImpedanceFileFormat hint = ImpedanceFileFormat::Auto);
ImportedImpedance read_impedance_any(std::istream& in, const std::string& name,
                                     const ImpedanceReadOptions& opt);
ImportedImpedance read_impedance_file(const std::string& path,
                                      ImpedanceFileFormat hint = ImpedanceFileFormat::Auto);
ImportedImpedance read_impedance_file(const std::string& path, const ImpedanceReadOptions& opt);

}  // namespace piezo::dsp
