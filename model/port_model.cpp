#include "model/port_model.hpp"

#include <cmath>
#include <stdexcept>

namespace piezo::model {

void RayleighDamping::validate() const {
  if (!(alpha >= 0) || !std::isfinite(alpha))
    throw std::invalid_argument("RayleighDamping::validate: alpha must be finite and >= 0");
  if (!(beta >= 0) || !std::isfinite(beta))
    throw std::invalid_argument("RayleighDamping::validate: beta must be finite and >= 0");
}

std::complex<double> ModalPortModel::charge_per_volt(double omega, const RayleighDamping& d,
                                                     const MaterialLosses& l) const {
  using cd = std::complex<double>;
  const double eta = std::isfinite(l.qm) ? 1.0 / l.qm : 0.0;
  cd q = c_clamped * cd(1.0, -l.tan_delta) + c_residual;
  for (const auto& m : modes) {
    const cd den(m.omega * m.omega - omega * omega,
                 omega * (d.alpha + d.beta * m.kappa) + eta * m.kappa);
    q += m.participation * m.participation / den;
  }
  return q;
}

}  // namespace piezo::model
