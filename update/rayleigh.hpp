#pragma once
// Rayleigh damping C = αM + βK from the damping ratios of two modes, seed
// eqs 166-169: ξ_n = ½(α/ω_n + βω_n) solved for α, β. A negative α or β is
// not a damping model (it feeds energy into some band): refused, with the
// reason, instead of being used.
#include <limits>
#include <string>

#include "model/port_model.hpp"

namespace piezo::update {

struct RayleighFit {
  bool ok = false;
  std::string message;             // why not, when !ok
  model::RayleighDamping damping;  // α (1/s), β (s); the raw solution even when refused
};

// kappa_ratio_k = κ_k/ω_k² of the model's mode (κ_k = φ_kᵀK_UUφ_k, model/port_model.hpp):
// the FE damps with the mechanical stiffness K_UU only, while the short-circuit
// ω_k² also holds the piezoelectric stiffening, so the model's modal damping is
// 2ω_kξ_k = α + βκ_k. With 1 (the default) this is the seed's eq. 167,
// ξ = α/2ω + βω/2; for two modes 6 % apart the ratios 0.9997 and 0.9910 of the
// APC850 tube move β by −7.8 % and α from 0 to +777 1/s if left out.
RayleighFit rayleigh_from_damping(double f1_hz, double zeta1, double f2_hz, double zeta2,
                                  double kappa_ratio1 = 1.0, double kappa_ratio2 = 1.0);

// What a normal run uses (issue 19): the two-parameter fit above when it is
// physical, else what the two modes' damping does support — a one-parameter
// damping fitted by least squares to both modes (stiffness-proportional
// 2ω_kξ_k = βκ_k when α < 0, mass-proportional 2ω_kξ_k = α when β < 0), its
// sigma from the two modes' disagreement (one degree of freedom) — and always
// the measured per-mode loss Qm_k = 1/(2ξ_k). A measured loss with a sigma,
// never a refusal; ok = false only for unusable input (message says why).
struct ModeDamping {
  bool ok = false;
  std::string message;             // unusable input, when !ok
  model::RayleighDamping damping;  // α, β ≥ 0
  // "rayleigh (alpha, beta)" | "stiffness-proportional (beta only)" |
  // "mass-proportional (alpha only)"
  std::string model;
  std::string note;  // why one parameter (the two-parameter solution's numbers)
  // 1σ of the one-parameter fit from the two modes' scatter about it (NaN for
  // the exact two-parameter solution: no degree of freedom left).
  double alpha_sigma = std::numeric_limits<double>::quiet_NaN();
  double beta_sigma = std::numeric_limits<double>::quiet_NaN();
  double qm1 = 0, qm2 = 0;  // measured Qm of each mode, 1/(2ξ)
};
ModeDamping damping_from_modes(double f1_hz, double zeta1, double f2_hz, double zeta2,
                               double kappa_ratio1 = 1.0, double kappa_ratio2 = 1.0);

}  // namespace piezo::update
