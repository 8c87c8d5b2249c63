#pragma once
// What a pair of numbers per frequency means, and the impedance it gives.
// Shared by the table readers (columns.hpp names the columns) and the 4294A
// reader (its MEASURE PARAMETER names the traces).
//   polar:        |Z| or |Y| or |S11| (linear or dB) and phase
//   rectangular:  R and X, G and B, Re and Im of S11
//   series:       Ls or Cs with Rs, D or Q       (Z = Rs + jX)
//   parallel:     Lp or Cp with G, Rp, D or Q    (Y = G + jB)
// S11 becomes Z = z0 (1 + S)/(1 − S); Y becomes Z = 1/Y; S21 (transmission)
// becomes the impedance of a device in series between the two ports (the
// series-through fixture crystals are measured in): Z = 2·z0·(1 − S21)/S21.
#include <complex>
#include <string>

namespace piezo::dsp::zfiles {

enum class Quantity { Unknown, Z, Y, S, S21 };
enum class Part { None, Mag, MagDb, Phase, Re, Im, Ls, Cs, Lp, Cp, Rp, D, Q };

struct PairSpec {
  Quantity quantity = Quantity::Z;
  Part a = Part::Re, b = Part::Im;  // canonical order: magnitude / real part / L or C first
  double z0_ohm = 50.0;             // reference of S11 or S21
};

// True for the pairs listed above (in canonical order; Quantity must be known:
// Z for series, Y for parallel).
bool valid_pair(Quantity q, Part a, Part b);

// Z in ohm from one point's values in SI units (angles in rad; a dB magnitude is
// 20·log10 of the magnitude in ohm, siemens or 1). A negative linear magnitude
// gives NaN (refused by the curve check).
std::complex<double> to_impedance(const PairSpec& p, double f_hz, double a, double b);

// "impedance |Z| and phase", "admittance G and B", "S11 (dB and phase), z0 = 75 ohm", ...
std::string describe(const PairSpec& p);

const char* part_name(Part p);

}  // namespace piezo::dsp::zfiles
