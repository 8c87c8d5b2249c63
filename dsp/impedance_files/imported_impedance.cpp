#include "dsp/impedance_files/imported_impedance.hpp"

namespace piezo::dsp {

const char* to_string(ImpedanceFileFormat f) {
  switch (f) {
    case ImpedanceFileFormat::Auto:
      return "auto";
    case ImpedanceFileFormat::Touchstone:
      return "touchstone";
    case ImpedanceFileFormat::Hp4294a:
      return "hp4294a";
    case ImpedanceFileFormat::E4990a:
      return "e4990a";
    case ImpedanceFileFormat::Bode100:
      return "bode100";
    case ImpedanceFileFormat::Table:
      return "table";
    case ImpedanceFileFormat::Hioki:
      return "hioki";
    case ImpedanceFileFormat::LabOne:
      return "labone";
  }
  return "?";
}

}  // namespace piezo::dsp
