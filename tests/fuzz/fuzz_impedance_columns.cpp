// Fuzz harness: a table read with the column names given (`piezobench figures --columns`,
// dsp/impedance_files/columns.hpp's parse_column_spec, then table.hpp). The input's first line
// is the specification, the rest the file. Documented rejection: std::invalid_argument (a bad
// specification or a file that does not fit it). An accepted curve keeps the promises of
// impedance_files_check.hpp, comes from the table reader, and is magnitude-only exactly when
// its impedances are real and >= 0 by construction (|Z| + 0j).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>

#include "tests/fuzz/impedance_files_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const auto nl = text.find('\n');
  piezo::dsp::ImpedanceReadOptions opt;
  const std::string spec = text.substr(0, nl);
  opt.columns = spec.empty() ? std::string(1, 'f') : spec;  // (assigning "f": a gcc 12 -Wrestrict false positive)
  std::istringstream in(nl == std::string::npos ? std::string() : text.substr(nl + 1));
  try {
    const auto c = piezo::dsp::read_impedance_any(in, "x.txt", opt);
    piezo::fuzz::check_imported(c, "columns");
    FUZZ_CHECK(c.format == piezo::dsp::ImpedanceFileFormat::Table, "columns: format %s",
               piezo::dsp::to_string(c.format));
  } catch (const std::invalid_argument& e) {
    if (std::getenv("PIEZO_FUZZ_DEBUG")) std::fprintf(stderr, "refused: %s\n", e.what());
  }
  return 0;
}
