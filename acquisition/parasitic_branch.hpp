#pragma once
// A parasitic series R-L-C branch across the tube's terminals (issue 21: an
// out-of-catalogue cause for the simulated bench — a spurious resonance of a
// mount, a second piezo element, a resonant cable stub; the gap diagnosis has
// no effect for it). Its admittance
//     Y_b(ω) = jωC / (1 − ω²LC + jωRC)
// is one more term of the port's modal sum jω·p²/(ω_k² − ω² + jω c_k) with
//     p² = 1/L,  ω_k² = 1/(LC),  c_k = R/L                 (port_model.hpp)
// so the state-space bench realises it as an extra "mode" (divider_state_space.cpp).
//
// Specified by what a measurement would show: the series resonance f (where
// the branch is resistive), the effective coupling k_eff and the quality
// factor Q of the branch, relative to the capacitance C_t it sits across:
//     fs = 1/(2π√(L C)),  fp = 1/(2π√(L·C·C_t/(C + C_t)))   (C_t ∥ branch, lossless)
//     k_eff² = (fp² − fs²)/fp² = C/(C + C_t)  ⇒  C = C_t·k²/(1 − k²)
//     L = 1/((2π fs)²·C),  Q = √(L/C)/R  ⇒  R = √(L/C)/Q
// (C_t constant: near fs the tube is taken as its static capacitance; with the
// tube's modes nearby, k_eff is nominal).
namespace piezo::acq {

struct ParasiticBranch {  // element values
  double r_ohm = 0, l_h = 0, c_f = 0;
};

struct ParasiticResonance {  // what a measurement shows
  double f_hz = 0;   // series resonance
  double k_eff = 0;  // effective coupling against the tube's capacitance, 0 < k < 1
  double q = 0;      // sqrt(L/C)/R, > 0
};

// Throws std::invalid_argument for f ≤ 0, k ∉ (0, 1), Q ≤ 0 or C_t ≤ 0.
ParasiticBranch parasitic_branch(const ParasiticResonance& r, double c_tube_f);

}  // namespace piezo::acq
