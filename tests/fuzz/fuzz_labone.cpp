// Fuzz harness: the reader of dsp/impedance_files/labone.hpp (Zurich Instruments LabOne exports), forced, then
// read_impedance_any on the same text (impedance_files_check.hpp states the promises checked and
// the documented rejection).
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/impedance_files_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return piezo::fuzz::run_impedance_reader(data, size, piezo::dsp::ImpedanceFileFormat::LabOne,
                                           "x.csv");
}
