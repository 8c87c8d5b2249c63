#include "dsp/impedance_types.hpp"

#include <cmath>
#include <stdexcept>

namespace piezo::dsp {

Eigen::VectorXd make_grid(double fmin_hz, double fmax_hz, double step_hz) {
  if (!(fmin_hz >= 0) || !(fmax_hz > fmin_hz) || !(step_hz > 0) || !std::isfinite(fmax_hz))
    throw std::invalid_argument("make_grid: need 0 <= fmin < fmax and step > 0");
  const double n = std::floor((fmax_hz - fmin_hz) / step_hz + 1e-9) + 1;
  if (n > 1e7) throw std::invalid_argument("make_grid: more than 1e7 points");
  return Eigen::VectorXd::LinSpaced(static_cast<Eigen::Index>(n), fmin_hz,
                                    fmin_hz + step_hz * (n - 1));
}

}  // namespace piezo::dsp
