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
  // εS → εS·s, s = 1 − j·tanδ, scales the whole potential block K_ΦΦ by s.
  // Condensing the potentials (the electrode V kept, the internal ones Φ_i
  // eliminated, eqs 87-92):
  //   C0    = −(K_VV − K_VΦi K_ΦiΦi⁻¹ K_ΦiV)            → C0·s           (exact)
  //   g     =  K_UV − K_UΦi K_ΦiΦi⁻¹ K_ΦiV              → g               (exact: s/s)
  //   K_sc  =  K_UU − K_UΦi K_ΦiΦi⁻¹ K_ΦiU              → K_UU + (K_sc − K_UU)/s
  // so the piezoelectric stiffening of each mode, φ_kᵀ(K_sc − K_UU)φ_k =
  // ω_k² − κ_k, becomes (ω_k² − κ_k)/s ≈ (ω_k² − κ_k)(1 + j·tanδ): the loss
  // inside the wall damps each mode in proportion to its electrical share of
  // stiffness (the modes' coupling through it, off the diagonal, is dropped:
  // first order). With the elastic loss K_UU → K_UU(1 + jη), η = 1/Qm:
  //   den_k = κ_k(1 + jη) + (ω_k² − κ_k)/s − ω² + jω(α + βκ_k).
  // The residual pseudo-mode has κ = ω² (modal.cpp): no stiffening share.
  const cd s(1.0, -l.tan_delta);
  cd q = c_clamped * s + c_residual;
  for (const auto& m : modes) {
    const double w2 = m.omega * m.omega;
    const double im = omega * (d.alpha + d.beta * m.kappa) + eta * m.kappa;
    const cd den = l.tan_delta == 0.0 ? cd(w2 - omega * omega, im)
                                      : cd(m.kappa - omega * omega, im) + (w2 - m.kappa) / s;
    q += m.participation * m.participation / den;
  }
  return q;
}

}  // namespace piezo::model
