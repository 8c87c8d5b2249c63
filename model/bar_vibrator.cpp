// The 33- and 31-mode bar vibrators of the seed's Appendix A (bar_vibrator.hpp).
//
// Notation: s the wave's compliance, ρ the density, κ = ω√(ρs) the
// wavenumber, A = w·h, m = ρAL; u(x) = B1 sin κx + B2 cos κx solves ρü = ∂T/∂x.
//
// 31 mode, E = V/h uniform, T1 = (S1 - d31E)/sE11, D3 = (d31/sE11)S1 + εT33(1 - k31²)E,
// Q = w∫D3 dx = w[(d31/sE11)(u(L) - u(0)) + LεT33(1 - k31²)E]:
//   free-free  T1(0) = T1(L) = 0 gives u(L) - u(0) = (2d31E/κ)tan(κL/2), so
//              Y/(jω) = Cf[(1 - k31²) + k31² tan(x)/x], x = κL/2 (IEEE Std 176);
//   fixed-mass u(0) = 0 and A·T1(L) = ω²M·u(L) give B1 = (A d31 E/sE11)/Dm,
//              Dm = Aκ cos(κL)/sE11 - ω²M sin(κL), so
//              Y/(jω) = (w/h)[(A d31²/sE11²) sin(κL) + LεT33(1 - k31²)Dm] / Dm.
// 33 mode, D uniform, T3 = (S3 - g33 D)/sD33, g33 = d33/εT33,
// V = ∫E dx = (DL - d33∫T3 dx)/εT33, Q = DA:
//   free-free  Y/(jω) = C0 / [1 - k33² tan(x)/x], C0 = εT33(1 - k33²)A/L (IEEE Std 176);
//   fixed-mass B1 = (A g33 D/sD33)/Dm (Dm with sD33), so
//              Y/(jω) = AεT33 Dm / [L Dm/(1 - k33²) - (A d33 g33/sD33²) sin(κL)].
// Each tends to the free capacitance as ω → 0.
#include "model/bar_vibrator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace piezo::model {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("bar_vibrator: " + what);
}

struct Fraction {
  double num = 0, den = 0;  // Y/(jω) = num/den
};

Fraction fraction(const PiezoMaterialD& mat, const BarGeometry& g, BarMode mode, BarEnds ends,
                  const BarConstants& bc, double omega) {
  const double s = bc.compliance, k2 = bc.k * bc.k, l = g.length_m;
  const double area = g.width_m * g.thickness_m;
  const double kappa = omega * std::sqrt(g.density_kg_m3 * s);
  const double x = 0.5 * kappa * l;
  const double dm = area * kappa * std::cos(kappa * l) / s - omega * omega * g.end_mass_kg * std::sin(kappa * l);
  if (mode == BarMode::m31) {
    if (ends == BarEnds::free_free)
      return {bc.c_free * ((1.0 - k2) * std::cos(x) + k2 * std::sin(x) / x), std::cos(x)};
    const double d31 = mat.d31;
    return {(g.width_m / g.thickness_m) *
                (area * d31 * d31 / (s * s) * std::sin(kappa * l) + l * mat.eps_t33 * (1.0 - k2) * dm),
            dm};
  }
  if (ends == BarEnds::free_free) return {bc.c_clamped * std::cos(x), std::cos(x) - k2 * std::sin(x) / x};
  const double g33 = mat.d33 / mat.eps_t33;
  return {area * mat.eps_t33 * dm, l * dm / (1.0 - k2) - area * mat.d33 * g33 / (s * s) * std::sin(kappa * l)};
}

// A zero of f in [a, b] (f(a), f(b) of opposite signs), to a relative 1e-13.
template <typename F>
double bisect(F f, double a, double b) {
  double fa = f(a);
  for (int i = 0; i < 200 && (b - a) > 1e-13 * b; ++i) {
    const double m = 0.5 * (a + b);
    const double fm = f(m);
    if ((fm < 0) == (fa < 0)) {
      a = m;
      fa = fm;
    } else {
      b = m;
    }
  }
  return 0.5 * (a + b);
}

}  // namespace

const char* to_string(BarMode m) { return m == BarMode::m33 ? "33" : "31"; }
const char* to_string(BarEnds e) { return e == BarEnds::free_free ? "free-free" : "fixed-mass"; }

void BarGeometry::validate() const {
  auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  require(positive(length_m), "length_m must be > 0");
  require(positive(width_m), "width_m must be > 0");
  require(positive(thickness_m), "thickness_m must be > 0");
  require(positive(density_kg_m3), "density_kg_m3 must be > 0");
  require(std::isfinite(end_mass_kg) && end_mass_kg >= 0, "end_mass_kg must be finite and >= 0");
}

BarConstants bar_constants(const PiezoMaterialD& m, const BarGeometry& g, BarMode mode) {
  g.validate();
  require(std::isfinite(m.eps_t33) && m.eps_t33 > 0, "epsT33 must be > 0");
  BarConstants c;
  if (mode == BarMode::m33) {
    require(std::isfinite(m.s_e33) && m.s_e33 > 0, "sE33 must be > 0 for the 33 mode");
    require(std::isfinite(m.d33), "d33 must be finite");
    const double k2 = m.d33 * m.d33 / (m.s_e33 * m.eps_t33);
    require(k2 < 1, "k33 must be < 1 (d33^2 < sE33 epsT33)");
    c.k = std::sqrt(k2);
    c.compliance = m.s_e33 * (1.0 - k2);
    c.c_free = m.eps_t33 * g.width_m * g.thickness_m / g.length_m;
  } else {
    require(std::isfinite(m.s_e11) && m.s_e11 > 0, "sE11 must be > 0 for the 31 mode");
    require(std::isfinite(m.d31), "d31 must be finite");
    const double k2 = m.d31 * m.d31 / (m.s_e11 * m.eps_t33);
    require(k2 < 1, "k31 must be < 1 (d31^2 < sE11 epsT33)");
    c.k = std::sqrt(k2);
    c.compliance = m.s_e11;
    c.c_free = m.eps_t33 * g.width_m * g.length_m / g.thickness_m;
  }
  c.c_clamped = (1.0 - c.k * c.k) * c.c_free;
  return c;
}

std::complex<double> bar_admittance(const PiezoMaterialD& material, const BarGeometry& geometry, BarMode mode,
                                    BarEnds ends, double omega) {
  require(std::isfinite(omega) && omega > 0, "omega must be > 0");
  const BarConstants bc = bar_constants(material, geometry, mode);
  const Fraction f = fraction(material, geometry, mode, ends, bc, omega);
  return {0.0, omega * f.num / f.den};
}

std::vector<BarResonance> bar_resonances(const PiezoMaterialD& material, const BarGeometry& geometry,
                                         BarMode mode, BarEnds ends, double fmax_hz, int points) {
  require(std::isfinite(fmax_hz) && fmax_hz > 0, "fmax_hz must be > 0");
  require(points >= 16, "points must be >= 16");
  const BarConstants bc = bar_constants(material, geometry, mode);
  auto num = [&](double f) { return fraction(material, geometry, mode, ends, bc, kTwoPi * f).num; };
  auto den = [&](double f) { return fraction(material, geometry, mode, ends, bc, kTwoPi * f).den; };
  std::vector<double> fr, fa;
  const double step = fmax_hz / points;
  double prev_f = step, prev_n = num(prev_f), prev_d = den(prev_f);
  for (int i = 2; i <= points; ++i) {
    const double f = step * i;
    const double n = num(f), d = den(f);
    if ((n < 0) != (prev_n < 0)) fa.push_back(bisect(num, prev_f, f));
    if ((d < 0) != (prev_d < 0)) fr.push_back(bisect(den, prev_f, f));
    prev_f = f;
    prev_n = n;
    prev_d = d;
  }
  std::vector<BarResonance> out;
  for (std::size_t i = 0; i < fr.size(); ++i) {
    BarResonance r;
    r.resonance_hz = fr[i];
    const double next = i + 1 < fr.size() ? fr[i + 1] : INFINITY;
    const auto a = std::find_if(fa.begin(), fa.end(), [&](double v) { return v > fr[i] && v < next; });
    if (a != fa.end()) {
      r.antiresonance_hz = *a;
      r.k_eff = std::sqrt(std::max(0.0, 1.0 - (fr[i] / *a) * (fr[i] / *a)));
    }
    out.push_back(r);
  }
  return out;
}

}  // namespace piezo::model
