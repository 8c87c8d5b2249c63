#include "update/rayleigh.hpp"

#include <cmath>
#include <limits>
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

ModeDamping damping_from_modes(double f1_hz, double zeta1, double f2_hz, double zeta2,
                               double kappa_ratio1, double kappa_ratio2) {
  ModeDamping out;
  const RayleighFit two =
      rayleigh_from_damping(f1_hz, zeta1, f2_hz, zeta2, kappa_ratio1, kappa_ratio2);
  if (two.ok) {
    out.ok = true;
    out.damping = two.damping;
    out.model = "rayleigh (alpha, beta)";
  } else if (two.damping.alpha < 0 || two.damping.beta < 0) {
    // Input was usable (the solution exists) but not physical: fit one
    // parameter to both modes. y_k = 2ω_kξ_k = a·x_k with x_k = κ_k (β only)
    // or 1 (α only); least squares a = Σx y / Σx², s² = Σ(y − a x)²/(2 − 1),
    // σ_a = s/sqrt(Σx²).
    const double w1 = 2 * M_PI * f1_hz, w2 = 2 * M_PI * f2_hz;
    const double y[2] = {2 * zeta1 * w1, 2 * zeta2 * w2};
    const bool beta_only = two.damping.alpha < 0;
    const double x[2] = {beta_only ? kappa_ratio1 * w1 * w1 : 1.0,
                         beta_only ? kappa_ratio2 * w2 * w2 : 1.0};
    const double sxx = x[0] * x[0] + x[1] * x[1];
    const double a = (x[0] * y[0] + x[1] * y[1]) / sxx;
    const double r0 = y[0] - a * x[0], r1 = y[1] - a * x[1];
    const double sigma = std::sqrt((r0 * r0 + r1 * r1) / sxx);
    std::ostringstream n;
    n.precision(4);
    n << "the two-parameter Rayleigh solution has " << (beta_only ? "alpha = " : "beta = ")
      << (beta_only ? two.damping.alpha : two.damping.beta) << (beta_only ? " 1/s" : " s")
      << " < 0 (zeta " << zeta1 << " at " << f1_hz << " Hz, " << zeta2 << " at " << f2_hz
      << " Hz): the damping these modes support is " << (beta_only ? "stiffness" : "mass")
      << "-proportional, fitted to both";
    out.ok = true;
    out.note = n.str();
    if (beta_only) {
      out.damping = {0.0, a};
      out.beta_sigma = sigma;
      out.model = "stiffness-proportional (beta only)";
    } else {
      out.damping = {a, 0.0};
      out.alpha_sigma = sigma;
      out.model = "mass-proportional (alpha only)";
    }
  } else {
    out.message = two.message;
    return out;
  }
  out.qm1 = zeta1 > 0 ? 0.5 / zeta1 : std::numeric_limits<double>::infinity();
  out.qm2 = zeta2 > 0 ? 0.5 / zeta2 : std::numeric_limits<double>::infinity();
  return out;
}

}  // namespace piezo::update
