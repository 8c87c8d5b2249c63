#include "update/rayleigh.hpp"

#include <cmath>
#include <sstream>

namespace piezo::update {

RayleighFit rayleigh_from_damping(double f1_hz, double zeta1, double f2_hz, double zeta2,
                                  double kappa_ratio1, double kappa_ratio2) {
  RayleighFit r;
  if (!(f1_hz > 0) || !(f2_hz > 0) || !std::isfinite(f1_hz) || !std::isfinite(f2_hz)) {
    r.message = "rayleigh_from_damping: frequencies must be positive";
    return r;
  }
  if (std::abs(f1_hz - f2_hz) <= 1e-9 * std::max(f1_hz, f2_hz)) {
    r.message = "rayleigh_from_damping: the two modes must have different frequencies";
    return r;
  }
  if (!(zeta1 >= 0) || !(zeta2 >= 0) || !std::isfinite(zeta1) || !std::isfinite(zeta2)) {
    r.message = "rayleigh_from_damping: damping ratios must be finite and >= 0";
    return r;
  }
  if (!(kappa_ratio1 > 0) || !(kappa_ratio2 > 0) || !std::isfinite(kappa_ratio1) ||
      !std::isfinite(kappa_ratio2)) {
    r.message = "rayleigh_from_damping: stiffness ratios must be finite and > 0";
    return r;
  }
  const double w1 = 2 * M_PI * f1_hz, w2 = 2 * M_PI * f2_hz;
  // 2ω_kξ_k = α + βκ_k, κ_k = kappa_ratio_k·ω_k² (eqs 168-169 when the ratios are 1).
  const double k1 = kappa_ratio1 * w1 * w1, k2 = kappa_ratio2 * w2 * w2;
  if (std::abs(k2 - k1) <= 1e-12 * std::max(k1, k2)) {
    r.message = "rayleigh_from_damping: the two modes have the same modal stiffness";
    return r;
  }
  r.damping.beta = (2 * zeta2 * w2 - 2 * zeta1 * w1) / (k2 - k1);  // eq. 169
  r.damping.alpha = 2 * zeta1 * w1 - r.damping.beta * k1;           // eq. 168
  if (r.damping.alpha < 0 || r.damping.beta < 0) {
    std::ostringstream s;
    s.precision(4);
    s << "Rayleigh fit refused: " << (r.damping.alpha < 0 ? "alpha" : "beta") << " = "
      << (r.damping.alpha < 0 ? r.damping.alpha : r.damping.beta)
      << " is negative (non-physical): zeta " << zeta1 << " at " << f1_hz << " Hz and " << zeta2
      << " at " << f2_hz << " Hz cannot both come from C = alpha M + beta K";
    r.message = s.str();
    return r;
  }
  r.ok = true;
  return r;
}

}  // namespace piezo::update
