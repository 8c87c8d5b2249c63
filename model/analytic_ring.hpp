#pragma once
// The thin radially poled ring as a 3-1 single-degree-of-freedom vibrator
// (seed §2.3.1, eqs 25-55; Mason 2013): only the hoop stress T1 acts, the
// field E3 = V/t is uniform through the wall, and the whole ring breathes with
// one radial displacement u. Valid for wall t ≪ mean radius a and height ℓ ≪ a;
// the FE tube model (model/tube_model.hpp) tends to it in that limit, which
// tests/model/test_analytic_ring.cpp checks. Hoop is IEEE axis 2 of the tube;
// by transverse isotropy sE22 = sE11 and d32 = d31, so the seed writes 1.
#include <complex>

#include "model/material.hpp"
#include "model/tube_geometry.hpp"

namespace piezo::model {

// Ring dimensions as the seed's Fig 18 comparison uses them (§3.3.1).
struct RingGeometry {
  double mean_radius_m = 0;  // a = (Do + Di)/4
  double wall_m = 0;         // t = (Do − Di)/2
  double height_m = 0;       // ℓ (the tube's length L)
  double density_kg_m3 = 0;  // ρ
  void validate() const;     // throws std::invalid_argument naming the field
};

// a = (Do + Di)/4, t = (Do − Di)/2, ℓ = L, ρ of the tube.
RingGeometry ring_geometry(const TubeGeometry& tube);

// Everything eqs 29-55 define, SI units (rad/s, F, H, kg).
struct AnalyticRing {
  double k31 = 0;             // eq 29: k31² = d31²/(sE11 εT33), k31 ≥ 0
  double omega_r = 0;         // eqs 34, 42: ωr = ω1 = 1/(a sqrt(ρ sE11))
  double omega_a = 0;         // eq 43: ωa = ωr / sqrt(1 − k31²)
  double c_free = 0;          // eq 48: Cf = 2π a ℓ εT33 / t
  double c_clamped = 0;       // eq 47: C0 = Cf (1 − k31²) (laterally clamped, 1-D)
  double c_motional = 0;      // eq 50: C1 = Cf k31²
  double l_motional = 0;      // eq 54: L1 = 1/(ω1² C1)
  double mass_kg = 0;         // eq 55: M = 2π a t ℓ ρ
  double compliance_m_n = 0;  // eq 52: Cm = a sE11 / (2π ℓ t)
  double turns_ratio = 0;     // eq 53: N = 2π ℓ d31 / sE11 (C/m, sign of d31)
};

// Uses sE11, d31, εT33 of the d-form only (the 3-1 vibrator ignores the rest).
// Throws std::invalid_argument (naming the function) unless sE11 > 0,
// εT33 > 0, d31 finite and k31 < 1.
AnalyticRing analytic_ring(const PiezoMaterialD& material, const RingGeometry& geometry);

// Eq 41: Y(ω) = jω (2π a ℓ / t) εT33 [k31² ω1²/(ω1² − ω²) + 1 − k31²], lossless
// (infinite at ω = ωr, zero at ω = ωa). Throws for ω < 0 or non-finite.
std::complex<double> ring_admittance(const AnalyticRing& ring, double omega);

// Eq 44: k31 = sqrt(1 − (ωr/ωa)²) from a measured or computed pair; throws
// unless 0 < ωr ≤ ωa.
double k31_from_frequencies(double omega_r, double omega_a);

}  // namespace piezo::model
