#pragma once
// Rayleigh damping C = αM + βK (seed eq. 166) from modal damping ratios:
// ξ_n = (α/ω_n + β·ω_n)/2 (eq. 167); from two modes α, β by eqs 168-169, from
// more by least squares on eq. 167.
#include <span>

#include "dsp/impedance_types.hpp"

namespace piezo::dsp {

struct RayleighDamping {
  double alpha = 0.0;  // 1/s
  double beta = 0.0;   // s
};

// Eqs 168-169; ω in rad/s. Throws if ω1 == ω2.
RayleighDamping rayleigh_from_two_modes(double omega1, double xi1, double omega2, double xi2);
// Least squares on eq. 167 over >= 2 modes (f in Hz, ξ from PoleInfo).
RayleighDamping rayleigh_fit(std::span<const PoleInfo> modes);
// Eq. 167.
double rayleigh_damping_ratio(const RayleighDamping& d, double omega);

}  // namespace piezo::dsp
