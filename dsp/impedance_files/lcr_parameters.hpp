#pragma once
// Two parameters of an LCR meter or impedance analyzer to Z, whatever pair the
// operator chose on the instrument (HIOKI IM3570/IM3536/IM7580: |Z|, Y, θ, Rs,
// Rp, X, G, B, Cs, Cp, Ls, Lp, D, Q, any two; a table's columns the polar and
// rectangular forms of quantities.hpp do not cover). Each value is first put
// in one of seven kinds (|Y| -> |Z| = 1/|Y|, θ of Y -> θ of Z = −θy, Rp -> G = 1/Rp,
// Cs -> X = −1/(ωCs), Ls -> X = ωLs, Cp -> B = ωCp, Lp -> B = −1/(ωLp), Q -> D = 1/Q):
//   complex Z   |Z| θ; R X; G B; X D (R = D|X|); B D (G = D|B|); θ R; θ X; θ G;
//               θ B; |Z| X (R = √(|Z|² − X²)); |Z| B (X = −B|Z|², R as before);
//               X B (|Z|² = −X/B): R ≥ 0 (a passive part) is assumed where only
//               R² is known, and said in a note
//   |Z| only    |Z| alone; |Z| R, |Z| G, |Z| D, R D, G D, R G: the sign of X is
//               not in them
//   nothing     θ D, X G, R B, a parameter alone other than |Z|, two of one kind
#include <complex>
#include <optional>
#include <string>

namespace piezo::dsp::zfiles {

enum class Lcr { AbsZ, AbsY, Phase, PhaseY, R, X, G, B, Rp, Cs, Cp, Ls, Lp, D, Q };

struct LcrPair {
  Lcr a = Lcr::AbsZ;
  std::optional<Lcr> b;  // empty: a alone
  bool magnitude_only = false;
  std::string assumption;  // what was assumed, one sentence; empty when nothing
};

// How a and b (in either order; b empty: a alone) give Z, or nullopt when they
// give neither Z nor |Z|.
std::optional<LcrPair> lcr_pair(Lcr a, std::optional<Lcr> b);

// Z of one point (|Z| + 0j when magnitude_only) from the values of a and b in
// SI units (phases in rad). |X| above |Z| (rounding) gives R = 0; values that
// contradict the pair (|Z|² = −X/B < 0, a negative |Z|) give NaN.
std::complex<double> lcr_impedance(const LcrPair& p, double f_hz, double va, double vb);

// "|Z|", "θ", "Rs", "Cp", ...; "|Z| and X" for a pair.
const char* lcr_name(Lcr p);
std::string describe(const LcrPair& p);

}  // namespace piezo::dsp::zfiles
