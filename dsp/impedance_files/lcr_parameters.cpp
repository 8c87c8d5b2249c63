#include "dsp/impedance_files/lcr_parameters.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

namespace piezo::dsp::zfiles {

namespace {

// The seven kinds every parameter is put in.
enum class K { M, P, R, X, G, B, D };

K kind(Lcr p) {
  switch (p) {
    case Lcr::AbsZ:
    case Lcr::AbsY:
      return K::M;
    case Lcr::Phase:
    case Lcr::PhaseY:
      return K::P;
    case Lcr::R:
      return K::R;
    case Lcr::X:
    case Lcr::Cs:
    case Lcr::Ls:
      return K::X;
    case Lcr::G:
    case Lcr::Rp:
      return K::G;
    case Lcr::B:
    case Lcr::Cp:
    case Lcr::Lp:
      return K::B;
    case Lcr::D:
    case Lcr::Q:
      return K::D;
  }
  return K::D;
}

// The value of p in its kind.
double canonical(Lcr p, double f_hz, double v) {
  const double w = 2.0 * std::numbers::pi * f_hz;
  switch (p) {
    case Lcr::AbsY:
      return 1.0 / v;
    case Lcr::PhaseY:
      return -v;
    case Lcr::Rp:
      return 1.0 / v;
    case Lcr::Cs:
      return -1.0 / (w * v);
    case Lcr::Ls:
      return w * v;
    case Lcr::Cp:
      return w * v;
    case Lcr::Lp:
      return -1.0 / (w * v);
    case Lcr::Q:
      return 1.0 / v;
    default:
      return v;
  }
}

// 0: nothing; 1: |Z| only; 2: complex Z.
int pair_result(K a, K b) {
  if (a == b) return 0;
  if (a > b) std::swap(a, b);
  switch (a) {
    case K::M:
      return (b == K::P || b == K::X || b == K::B) ? 2 : 1;  // M R, M G, M D: |Z| only
    case K::P:
      return b == K::D ? 0 : 2;  // P R, P X, P G, P B
    case K::R:
      return b == K::X ? 2 : (b == K::G || b == K::D) ? 1 : 0;  // R B: two roots
    case K::X:
      return (b == K::B || b == K::D) ? 2 : 0;  // X G: two roots
    case K::G:
      return b == K::B ? 2 : 1;  // G D: |Y| only
    case K::B:
      return 2;  // B D
    case K::D:
      return 0;
  }
  return 0;
}

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// R (or G) from |Z| (or |Y|) and X (or B): √(m² − x²), 0 when rounding puts |x| above m.
double other_leg(double m, double x) {
  if (!(m >= 0)) return kNan;
  const double d = m * m - x * x;
  return d > 0 ? std::sqrt(d) : 0.0;
}

}  // namespace

const char* lcr_name(Lcr p) {
  switch (p) {
    case Lcr::AbsZ:
      return "|Z|";
    case Lcr::AbsY:
      return "|Y|";
    case Lcr::Phase:
      return "phase of Z";
    case Lcr::PhaseY:
      return "phase of Y";
    case Lcr::R:
      return "R";
    case Lcr::X:
      return "X";
    case Lcr::G:
      return "G";
    case Lcr::B:
      return "B";
    case Lcr::Rp:
      return "Rp";
    case Lcr::Cs:
      return "Cs";
    case Lcr::Cp:
      return "Cp";
    case Lcr::Ls:
      return "Ls";
    case Lcr::Lp:
      return "Lp";
    case Lcr::D:
      return "D";
    case Lcr::Q:
      return "Q";
  }
  return "?";
}

std::optional<LcrPair> lcr_pair(Lcr a, std::optional<Lcr> b) {
  LcrPair p;
  p.a = a;
  p.b = b;
  if (!b) {
    if (kind(a) != K::M) return std::nullopt;
    p.magnitude_only = true;
    p.assumption = std::string("only ") + lcr_name(a) + " in the file: read as |Z| alone (no phase)";
    return p;
  }
  const K ka = kind(a), kb = kind(*b);
  const int r = pair_result(ka, kb);
  if (r == 0) return std::nullopt;
  p.magnitude_only = r == 1;
  const auto has = [&](K k) { return ka == k || kb == k; };
  if (p.magnitude_only) {
    p.assumption = std::string(lcr_name(a)) + " and " + lcr_name(*b) +
                   " do not give the sign of the reactance: read as |Z| alone (no phase)";
  } else if (has(K::M) && (has(K::X) || has(K::B))) {
    p.assumption = has(K::X) ? "R = sqrt(|Z|^2 - X^2) >= 0 assumed (a passive part; the sign of R "
                               "is not in |Z| and X)"
                             : "G = sqrt(|Y|^2 - B^2) >= 0 assumed (a passive part; the sign of G "
                               "is not in |Y| and B)";
  } else if (has(K::X) && has(K::B)) {
    p.assumption = "R = sqrt(-X/B - X^2) >= 0 assumed (a passive part)";
  }
  return p;
}

std::complex<double> lcr_impedance(const LcrPair& p, double f_hz, double va, double vb) {
  using cd = std::complex<double>;
  K ka = kind(p.a);
  double a = canonical(p.a, f_hz, va);
  if (!p.b) return (ka == K::M && a >= 0) ? cd(a, 0) : cd(kNan, kNan);
  K kb = kind(*p.b);
  double b = canonical(*p.b, f_hz, vb);
  if (ka > kb) {
    std::swap(ka, kb);
    std::swap(a, b);
  }
  const auto mag = [](double m) { return m >= 0 ? cd(m, 0) : cd(kNan, kNan); };
  switch (ka) {
    case K::M:
      if (!(a >= 0)) return {kNan, kNan};
      switch (kb) {
        case K::P:
          return {a * std::cos(b), a * std::sin(b)};
        case K::X:
          return {other_leg(a, b), b};
        case K::B: {
          const double x = -b * a * a;
          return {other_leg(a, x), x};
        }
        default:  // R, G, D: |Z| only
          return {a, 0};
      }
    case K::P:
      switch (kb) {
        case K::R:
          return {b, b * std::tan(a)};
        case K::X:
          return {b / std::tan(a), b};
        case K::G:
          return 1.0 / cd(b, b * std::tan(-a));
        case K::B:
          return 1.0 / cd(b / std::tan(-a), b);
        default:
          return {kNan, kNan};
      }
    case K::R:
      switch (kb) {
        case K::X:
          return {a, b};
        case K::G:  // |Z|² = R/G
          return (a >= 0 && b > 0) ? mag(std::sqrt(a / b)) : cd(kNan, kNan);
        case K::D:  // |X| = R/D
          return mag(std::hypot(a, a / b));
        default:
          return {kNan, kNan};
      }
    case K::X:
      switch (kb) {
        case K::B: {  // |Z|² = −X/B
          const double m2 = -a / b;
          if (!(m2 >= 0)) return {kNan, kNan};
          return {other_leg(std::sqrt(m2), a), a};
        }
        case K::D:
          return {b * std::abs(a), a};
        default:
          return {kNan, kNan};
      }
    case K::G:
      switch (kb) {
        case K::B:
          return 1.0 / cd(a, b);
        case K::D:  // |B| = G/D, |Z| = 1/|Y|
          return mag(1.0 / std::hypot(a, a / b));
        default:
          return {kNan, kNan};
      }
    case K::B:
      if (kb == K::D) return 1.0 / cd(b * std::abs(a), a);
      return {kNan, kNan};
    case K::D:
      break;
  }
  return {kNan, kNan};
}

std::string describe(const LcrPair& p) {
  std::string s = lcr_name(p.a);
  if (p.b) s += std::string(" and ") + lcr_name(*p.b);
  return s + (p.magnitude_only ? " (|Z| only)" : "");
}

}  // namespace piezo::dsp::zfiles
