#include "model/port_model.hpp"

#include <algorithm>
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

void add_residual_mode(ModalPortModel& p, double shape_mass) {
  double sum1 = 0, sum2 = 0, omega_max = 0;
  for (const auto& m : p.modes) {
    const double p2w2 = m.participation * m.participation / (m.omega * m.omega);
    sum1 += p2w2;
    sum2 += p2w2 / (m.omega * m.omega);
    omega_max = std::max(omega_max, m.omega);
  }
  const double r1 = p.c_static - p.c_clamped - sum1;
  const double r2 = shape_mass - sum2;
  p.c_residual = r1;
  if (r1 > 0 && r2 > 0 && r1 / r2 > omega_max * omega_max) {
    const double wr = std::sqrt(r1 / r2);
    PortMode res;
    res.omega = wr;
    res.participation = std::sqrt(r1) * wr;
    res.kappa = wr * wr;  // K_UU ≈ K_sc for the high modes it stands for
    res.symmetric = true;
    res.residual = true;  // no radiation damping: it stands for modes whose shapes are not computed
    p.modes.push_back(res);
    p.c_residual = 0.0;
  }
}

void half_to_whole(ModalPortModel& p) {
  // Whole tube = two mirrored halves in parallel: every charge doubles, so C0,
  // C_static and the residual static share double, and a mode normalised on
  // the whole tube (φᵀMφ = 1 = 2·φ_halfᵀM_halfφ_half) has p² = 2·p_half²;
  // ω and κ = φᵀK_UUφ/φᵀMφ are the half's, and so is the radiation damping:
  // the whole tube's outer surface is the half's and its mirror image, so
  // φᵀC_aφ = 2·(φ_half/√2)ᵀC_a,half(φ_half/√2) = φ_halfᵀC_a,halfφ_half.
  p.c_clamped *= 2.0;
  p.c_static *= 2.0;
  p.c_residual *= 2.0;
  for (auto& m : p.modes) m.participation *= std::sqrt(2.0);
}

}  // namespace piezo::model
