#include "dsp/impedance_files/quantities.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

namespace piezo::dsp::zfiles {

namespace {
bool series_part(Part p) { return p == Part::Ls || p == Part::Cs; }
bool parallel_part(Part p) { return p == Part::Lp || p == Part::Cp; }
}  // namespace

bool valid_pair(Quantity q, Part a, Part b) {
  if (q == Quantity::Unknown) return false;
  if ((a == Part::Mag || a == Part::MagDb) && b == Part::Phase) return true;
  if (a == Part::Re && b == Part::Im) return true;
  if (q == Quantity::Z && series_part(a)) return b == Part::Re || b == Part::D || b == Part::Q;
  if (q == Quantity::Y && parallel_part(a))
    return b == Part::Re || b == Part::Rp || b == Part::D || b == Part::Q;
  return false;
}

std::complex<double> to_impedance(const PairSpec& p, double f_hz, double a, double b) {
  using cd = std::complex<double>;
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  const double w = 2.0 * std::numbers::pi * f_hz;
  cd x;
  switch (p.a) {
    case Part::Mag:
    case Part::MagDb: {
      const double m = p.a == Part::Mag ? a : std::pow(10.0, a / 20.0);
      if (!(m >= 0)) return {nan, nan};
      x = cd(m * std::cos(b), m * std::sin(b));  // std::polar requires m >= 0 and finite
      break;
    }
    case Part::Re:
      x = cd(a, b);
      break;
    case Part::Ls:
    case Part::Cs: {  // series: Z = Rs + jX
      const double X = p.a == Part::Ls ? w * a : -1.0 / (w * a);
      const double R = p.b == Part::Re ? b : p.b == Part::D ? b * std::abs(X) : std::abs(X) / b;
      return {R, X};
    }
    case Part::Lp:
    case Part::Cp: {  // parallel: Y = G + jB
      const double B = p.a == Part::Cp ? w * a : -1.0 / (w * a);
      const double G = p.b == Part::Re   ? b
                       : p.b == Part::Rp ? 1.0 / b
                       : p.b == Part::D  ? b * std::abs(B)
                                         : std::abs(B) / b;
      return 1.0 / cd(G, B);
    }
    default:
      return {nan, nan};
  }
  switch (p.quantity) {
    case Quantity::Z:
      return x;
    case Quantity::Y:
      return 1.0 / x;
    case Quantity::S:
      return p.z0_ohm * (1.0 + x) / (1.0 - x);
    case Quantity::S21:
      return 2.0 * p.z0_ohm * (1.0 - x) / x;
    default:
      return {nan, nan};
  }
}

const char* part_name(Part p) {
  switch (p) {
    case Part::None:
      return "?";
    case Part::Mag:
      return "magnitude";
    case Part::MagDb:
      return "magnitude (dB)";
    case Part::Phase:
      return "phase";
    case Part::Re:
      return "real part";
    case Part::Im:
      return "imaginary part";
    case Part::Ls:
      return "Ls";
    case Part::Cs:
      return "Cs";
    case Part::Lp:
      return "Lp";
    case Part::Cp:
      return "Cp";
    case Part::Rp:
      return "Rp";
    case Part::D:
      return "D";
    case Part::Q:
      return "Q";
  }
  return "?";
}

std::string describe(const PairSpec& p) {
  const bool z = p.quantity == Quantity::Z, y = p.quantity == Quantity::Y;
  if (p.quantity == Quantity::S || p.quantity == Quantity::S21) {
    char ref[48];
    std::snprintf(ref, sizeof ref, "%.10g", p.z0_ohm);
    const char* form = p.a == Part::Mag     ? "magnitude and phase"
                       : p.a == Part::MagDb ? "dB and phase"
                                            : "real and imaginary parts";
    if (p.quantity == Quantity::S21)
      return std::string("transmission S21 (") + form + "), z0 = " + ref +
             " ohm, device in series between the ports";
    return std::string("reflection coefficient S11 (") + form + "), z0 = " + ref + " ohm";
  }
  const std::string what = z ? "impedance" : y ? "admittance" : "?";
  switch (p.a) {
    case Part::Mag:
      return what + (z ? " |Z|" : " |Y|") + " and phase";
    case Part::MagDb:
      return what + (z ? " |Z| in dB (re 1 ohm)" : " |Y| in dB (re 1 S)") + " and phase";
    case Part::Re:
      return what + (z ? " R and X" : " G and B");
    default:
      break;
  }
  const char* b = p.b == Part::Re ? (z ? "Rs" : "G") : part_name(p.b);
  return std::string(z ? "series " : "parallel ") + part_name(p.a) + " and " + b;
}

}  // namespace piezo::dsp::zfiles
