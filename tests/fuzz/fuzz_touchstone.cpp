// Fuzz harness: the reader of dsp/impedance_files/touchstone.hpp (Touchstone 1.x and 2.0, one
// port), forced, then read_impedance_any on the same text (impedance_files_check.hpp states the
// promises checked and the documented rejection).
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/impedance_files_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Named .s1p, then .s2p (the name decides a 1.x file's port count).
  piezo::fuzz::run_impedance_reader(data, size, piezo::dsp::ImpedanceFileFormat::Touchstone,
                                    "x.s1p");
  return piezo::fuzz::run_impedance_reader(data, size, piezo::dsp::ImpedanceFileFormat::Touchstone,
                                           "x.s2p");
}
