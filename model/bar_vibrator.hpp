#pragma once
// The seed's Appendix A: the 33- and 31-mode bar vibrators (eqs A.1-A.8;
// Sherman and Butler 2007, ch. 2), as distributed one-dimensional models.
//
//   33 mode (Fig A.1): a bar of length L along the poling axis 3, electrodes on
//     its end faces (area A = w·h), only T3 acts (eqs A.3-A.4). No free charge
//     inside, so D3 is uniform along the bar and the field is not: the wave
//     runs on sD33 = sE33(1 - k33²), k33² = d33²/(sE33 εT33).
//   31 mode (Fig A.2): the same bar poled across its thickness h, electrodes on
//     the faces w·L, only T1 acts along the length (eqs A.5, A.8). The field
//     E3 = V/h is uniform and the wave runs on sE11; k31² = d31²/(sE11 εT33).
//
// Ends: free-free (the IEEE Std 176 resonators), or the seed's figures: fixed
// at x = 0 and a mass M at x = L (M = 0: fixed-free, a quarter wave).
// u(x) = B1 sin kx + B2 cos kx in each case; the admittance Y = jωQ/V follows
// in closed form (derivation in bar_vibrator.cpp), written as
// Y/(jω) = num(ω)/den(ω) with num and den continuous, so the resonances (Y
// infinite) are the zeros of den and the anti-resonances (Y = 0) those of num.
//
// Lossless. The lateral strains of eqs A.1-A.2 / A.6-A.7 play no part (the
// sides are free). Checks: tests/model/test_bar_vibrator.cpp (IEEE Std 176's
// k formulas, kL·tan kL = m/M, the low-frequency capacitance, and the FE tube's
// length mode, a 31-mode vibrator when the tube is long and thin).
#include <complex>
#include <vector>

#include "model/material.hpp"

namespace piezo::model {

enum class BarMode { m33, m31 };
enum class BarEnds { free_free, fixed_mass };

const char* to_string(BarMode m);  // "33", "31"
const char* to_string(BarEnds e);  // "free-free", "fixed-mass"

struct BarGeometry {
  double length_m = 0.02;     // L (33: along the poling axis; 31: across it)
  double width_m = 0.005;     // w
  double thickness_m = 0.002; // h (31: the poled thickness between the electrodes)
  double density_kg_m3 = 7600.0;
  double end_mass_kg = 0.0;   // M (fixed-mass only)
  void validate() const;      // throws std::invalid_argument naming the field
  double mass_kg() const { return density_kg_m3 * length_m * width_m * thickness_m; }
};

struct BarConstants {
  double k = 0;          // k33 or k31 of the material (≥ 0)
  double compliance = 0; // the wave's: sD33 (33) or sE11 (31), m²/N
  double c_free = 0;     // free capacitance: εT33·A/L (33) or εT33·wL/h (31), F
  double c_clamped = 0;  // (1 - k²)·c_free: the 1-D "clamped" capacitance, F
};

// Throws std::invalid_argument unless the constants the mode uses are
// positive and finite and k < 1.
BarConstants bar_constants(const PiezoMaterialD& material, const BarGeometry& geometry, BarMode mode);

// Y(ω) = jω·num/den (siemens), lossless; ω > 0. Throws for ω ≤ 0 or non-finite.
std::complex<double> bar_admittance(const PiezoMaterialD& material, const BarGeometry& geometry, BarMode mode,
                                    BarEnds ends, double omega);

struct BarResonance {
  double resonance_hz = 0;      // Y infinite (series resonance)
  double antiresonance_hz = 0;  // Y = 0 above it (0 if none below the limit)
  double k_eff = 0;             // sqrt(1 - (fr/fa)²), Mason's effective coupling (0 without fa)
};

// The resonance / anti-resonance pairs below fmax_hz, ascending: the zeros of
// den and num located on a grid of `points` steps and refined by bisection to
// a relative 1e-13. Throws for fmax_hz ≤ 0 or points < 16.
std::vector<BarResonance> bar_resonances(const PiezoMaterialD& material, const BarGeometry& geometry,
                                         BarMode mode, BarEnds ends, double fmax_hz, int points = 4000);

}  // namespace piezo::model
