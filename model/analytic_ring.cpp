#include "model/analytic_ring.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace piezo::model {

namespace {

[[noreturn]] void fail(const char* fn, const std::string& what) {
  throw std::invalid_argument(std::string(fn) + ": " + what);
}

}  // namespace

void RingGeometry::validate() const {
  const char* fn = "RingGeometry::validate";
  if (!(mean_radius_m > 0) || !std::isfinite(mean_radius_m)) fail(fn, "mean_radius_m must be > 0");
  if (!(wall_m > 0) || !std::isfinite(wall_m)) fail(fn, "wall_m must be > 0");
  if (!(wall_m < 2 * mean_radius_m)) fail(fn, "wall_m must be < 2·mean_radius_m");
  if (!(height_m > 0) || !std::isfinite(height_m)) fail(fn, "height_m must be > 0");
  if (!(density_kg_m3 > 0) || !std::isfinite(density_kg_m3)) fail(fn, "density_kg_m3 must be > 0");
}

RingGeometry ring_geometry(const TubeGeometry& tube) {
  tube.validate();
  RingGeometry g;
  g.mean_radius_m = 0.25 * (tube.outer_diameter_m + tube.inner_diameter_m);  // §3.3.1
  g.wall_m = 0.5 * (tube.outer_diameter_m - tube.inner_diameter_m);
  g.height_m = tube.length_m;
  g.density_kg_m3 = tube.density_kg_m3;
  return g;
}

AnalyticRing analytic_ring(const PiezoMaterialD& m, const RingGeometry& g) {
  const char* fn = "analytic_ring";
  g.validate();
  if (!(m.s_e11 > 0) || !std::isfinite(m.s_e11)) fail(fn, "sE11 must be > 0");
  if (!(m.eps_t33 > 0) || !std::isfinite(m.eps_t33)) fail(fn, "epsT33 must be > 0");
  if (!std::isfinite(m.d31)) fail(fn, "d31 must be finite");
  const double a = g.mean_radius_m, t = g.wall_m, l = g.height_m, rho = g.density_kg_m3;
  AnalyticRing r;
  const double k2 = m.d31 * m.d31 / (m.s_e11 * m.eps_t33);  // eq 29
  if (!(k2 < 1)) fail(fn, "k31² = d31²/(sE11 εT33) must be < 1");
  r.k31 = std::sqrt(k2);
  r.omega_r = 1.0 / (a * std::sqrt(rho * m.s_e11));                            // eqs 34, 42
  r.omega_a = r.omega_r / std::sqrt(1.0 - k2);                                 // eq 43
  r.c_free = 2.0 * M_PI * a * l * m.eps_t33 / t;                               // eq 48
  r.c_clamped = r.c_free * (1.0 - k2);                                         // eq 47
  r.c_motional = r.c_free * k2;                                                // eq 50
  r.l_motional = k2 > 0 ? 1.0 / (r.omega_r * r.omega_r * r.c_motional) : 0.0;  // eq 54
  r.mass_kg = 2.0 * M_PI * a * t * l * rho;                                    // eq 55
  r.compliance_m_n = a * m.s_e11 / (2.0 * M_PI * l * t);                       // eq 52
  r.turns_ratio = 2.0 * M_PI * l * m.d31 / m.s_e11;                            // eq 53
  return r;
}

std::complex<double> ring_admittance(const AnalyticRing& r, double omega) {
  if (!(omega >= 0) || !std::isfinite(omega))
    fail("ring_admittance", "omega must be finite and >= 0");
  // Eq 41 written with Cf = 2π a ℓ εT33 / t (eq 48).
  const double w1 = r.omega_r * r.omega_r, k2 = r.k31 * r.k31;
  const double bracket = k2 * w1 / (w1 - omega * omega) + (1.0 - k2);
  return {0.0, omega * r.c_free * bracket};
}

double k31_from_frequencies(double omega_r, double omega_a) {
  if (!(omega_r > 0) || !(omega_a >= omega_r) || !std::isfinite(omega_a))
    fail("k31_from_frequencies", "need 0 < omega_r <= omega_a (finite)");
  const double q = omega_r / omega_a;
  return std::sqrt(1.0 - q * q);  // eq 44
}

}  // namespace piezo::model
