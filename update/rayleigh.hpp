#pragma once
// Rayleigh damping C = αM + βK from the damping ratios of two modes, seed
// eqs 166-169: ξ_n = ½(α/ω_n + βω_n) solved for α, β. A negative α or β is
// not a damping model (it feeds energy into some band): refused, with the
// reason, instead of being used.
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

}  // namespace piezo::update
