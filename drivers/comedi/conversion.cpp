// comedilib's raw-to-volts formulas (lib/range.c comedi_to_phys, lib/calib.c
// comedi_to_physical), for boards that are not comedilib: the simulated board
// converts as the library would, operation for operation.
#include "drivers/comedi/board.hpp"

namespace piezo::drivers::comedi {

double linear_to_phys(std::uint32_t raw, const Range& r, std::uint32_t maxdata) {
  double x = raw;
  x /= maxdata;
  x *= (r.max - r.min);
  x += r.min;
  return x;
}

double polynomial_to_phys(std::uint32_t raw, const Polynomial& p) {
  const double value = static_cast<double>(raw) - p.expansion_origin;
  double term = 1.0, result = 0.0;
  for (double c : p.coefficients) {
    result += c * term;
    term *= value;
  }
  return result;
}

}  // namespace piezo::drivers::comedi
