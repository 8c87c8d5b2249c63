#pragma once
// Complex division without libgcc's __divdc3 call, inlined: a·conj(b)/|b|²
// (one division) where |b|² is a safe normal number, Smith's algorithm (one
// ratio of the divisor's parts, then one reciprocal) beyond. std::complex's
// operator/ goes through __divdc3 (scaling by logb, the C99 Annex G infinity
// and NaN rules), which was 6 % of a corpus replay's CPU in the forward
// models' inner loops (issue 43). Accuracy: a few ulp of |a/b| in each part,
// no overflow for |b| up to the double range; a divisor with a non-finite or zero part
// pair falls back to std::complex's division (its Annex G results).
#include <cmath>
#include <complex>

namespace piezo::numerics {

inline std::complex<double> divide(std::complex<double> a, std::complex<double> b) {
  const double br = b.real(), bi = b.imag();
  // a·conj(b)/|b|² with one division where |b|² is safely a normal number
  // (the forward models' divisors, |b| between 1e-150 and 1e150) …
  if (const double n = br * br + bi * bi; n > 1e-300 && n < 1e300) {
    const double inv = 1.0 / n;
    return {(a.real() * br + a.imag() * bi) * inv, (a.imag() * br - a.real() * bi) * inv};
  }
  if (!std::isfinite(br) || !std::isfinite(bi) || (br == 0.0 && bi == 0.0)) return a / b;
  // … else Smith's (one ratio of the divisor's parts: no overflow).
  if (std::abs(br) >= std::abs(bi)) {
    const double r = bi / br, inv_d = 1.0 / (br + bi * r);
    return {(a.real() + a.imag() * r) * inv_d, (a.imag() - a.real() * r) * inv_d};
  }
  const double r = br / bi, inv_d = 1.0 / (br * r + bi);
  return {(a.real() * r + a.imag()) * inv_d, (a.imag() * r - a.real()) * inv_d};
}

// 1/b, the same way.
inline std::complex<double> reciprocal(std::complex<double> b) { return divide(1.0, b); }

}  // namespace piezo::numerics
